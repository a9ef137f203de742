//! Suite `analyze`: local thickness of the tori-ball block voxelised at
//! 256^3 on [-1, 1]^3, microfrep against PoreSpy's
//! `porespy.filters.local_thickness` (default method), pore space and solid
//! each, on the same voxels. Each side runs in its own fresh process (ours:
//! this binary with `--child`; PoreSpy: bench/porespy_thickness.py), so the
//! peak resident memory (VmHWM / ru_maxrss) is that of one measurement;
//! times cover the thickness call only (not sampling, loading or imports),
//! as wall seconds and as CPU seconds (user + system, all threads; steadier
//! when other jobs share the cores). A last case measures the pore space
//! again under a 96 MiB working-memory limit (slabs) and checks that the
//! figures are the same. Diameters are printed in voxels (`_vox`).
//! PoreSpy runs from the venv in `target/porespy-venv` (or the Python named
//! by `MICROFREP_PORESPY_PYTHON`); when missing, the suite tries
//! `python3 -m venv` + `pip install porespy` once and reports `na` if that
//! fails. Threads: ours uses all cores (rayon), PoreSpy what it picks.

use microfrep_analysis::grid::{Grid, Sampler};
use microfrep_analysis::thickness::{thickness_of_labels, PhaseThickness, ThicknessOptions};
use microfrep_core::Shape;

use microfrep_structures::examples::toriball;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

const N: usize = 256;
const PHASES: [(u8, &str); 2] = [(1, "pore"), (2, "solid")];

/// One side's measurement of one phase (diameters in voxels).
#[derive(Default, Debug)]
struct Side {
    seconds: f64,
    /// CPU seconds (user + system, all threads) of the call.
    cpu: f64,
    peak_mib: f64,
    /// PoreSpy: the process's peak before the call (Python, imports, the
    /// labels); ours: slabs used.
    extra: f64,
    mean: f64,
    median: f64,
    max: f64,
}

pub fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(2).collect();
    if args.first().map(String::as_str) == Some("--child") {
        return child(&args[1..]);
    }
    let dir = PathBuf::from("target/analyze-bench");
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let raw = dir.join(format!("toriball{N}.raw"));
    let tape = Shape::new(toriball());
    let grid = Grid::new([[-1.0; 3], [1.0; 3]], N).map_err(|e| e.to_string())?;
    let labels = Sampler::new(&tape, None, grid).all(&|_, _| {});
    std::fs::write(&raw, &labels).map_err(|e| e.to_string())?;
    let porosity = labels.iter().filter(|&&l| l == 1).count() as f64 / labels.len() as f64;
    drop(labels);
    let python = porespy_python(&dir);
    let (mut ours, mut theirs) = (Vec::new(), Vec::new());
    for (label, name) in PHASES {
        let o = our_side(&raw, label, None)?;
        let t = python
            .as_ref()
            .and_then(|py| match their_side(py, &raw, label) {
                Ok(t) => Some(t),
                Err(e) => {
                    eprintln!("bench/run analyze: PoreSpy failed: {e}");
                    None
                }
            });
        println!(
            "RESULT analyze_local_thickness_{N}_{name} microfrep_s={:.3} microfrep_peak_mib={:.0} \
             porespy_s={} porespy_peak_mib={} porespy_before_call_mib={} \
             microfrep_cpu_s={:.3} porespy_cpu_s={} \
             microfrep_mean_vox={:.3} porespy_mean_vox={} \
             microfrep_median_vox={:.3} porespy_median_vox={} microfrep_max_vox={:.3} porespy_max_vox={}",
            o.seconds,
            o.peak_mib,
            fmt(t.as_ref().map(|t| t.seconds), 3),
            fmt(t.as_ref().map(|t| t.peak_mib), 0),
            fmt(t.as_ref().map(|t| t.extra), 0),
            o.cpu,
            fmt(t.as_ref().map(|t| t.cpu), 3),
            o.mean,
            fmt(t.as_ref().map(|t| t.mean), 3),
            o.median,
            fmt(t.as_ref().map(|t| t.median), 3),
            o.max,
            fmt(t.as_ref().map(|t| t.max), 3),
        );
        ours.push(o);
        theirs.push(t);
    }
    // The pore space again under a 96 MiB working-memory limit: slabs with
    // a halo (17 voxels) wider than its largest ball, so the same figures.
    let limit = 96;
    let s = our_side(&raw, 1, Some(limit))?;
    let same = s.mean == ours[0].mean && s.median == ours[0].median && s.max == ours[0].max;
    println!(
        "RESULT analyze_local_thickness_{N}_pore_slabs microfrep_s={:.3} microfrep_peak_mib={:.0} \
         memory_limit_mib={limit} slabs={} same_as_one_window={same}",
        s.seconds, s.peak_mib, s.extra
    );
    let ms: f64 = ours.iter().map(|o| o.seconds).sum();
    // Both phases again on one thread (PoreSpy's call ran on one core here).
    let mut one = 0.0;
    for (label, _) in PHASES {
        one += our_side_with(&raw, label, None, Some(1))?.seconds;
    }
    let mc: f64 = ours.iter().map(|o| o.cpu).sum();
    let tc = theirs
        .iter()
        .map(|t| t.as_ref().map(|t| t.cpu))
        .sum::<Option<f64>>();
    let mp = ours.iter().map(|o| o.peak_mib).fold(0.0, f64::max);
    let (ts, tp) = if theirs.iter().all(Option::is_some) {
        let t: Vec<&Side> = theirs.iter().flatten().collect();
        (
            Some(t.iter().map(|t| t.seconds).sum::<f64>()),
            Some(t.iter().map(|t| t.peak_mib).fold(0.0, f64::max)),
        )
    } else {
        (None, None)
    };
    println!(
        "RESULT analyze_local_thickness_{N} microfrep_s={ms:.3} microfrep_peak_mib={mp:.0} \
         porespy_s={} porespy_peak_mib={} ratio={} microfrep_cpu_s={mc:.3} porespy_cpu_s={} \
         cpu_ratio={} microfrep_1thread_s={one:.3} ratio_1thread={} porosity={porosity:.4} \
         phases=pore+solid threads={}",
        fmt(ts, 3),
        fmt(tp, 0),
        fmt(ts.map(|t| t / ms), 2),
        fmt(tc, 3),
        fmt(tc.map(|t| t / mc), 2),
        fmt(ts.map(|t| t / one), 2),
        rayon::current_num_threads(),
    );
    Ok(())
}

fn fmt(v: Option<f64>, digits: usize) -> String {
    v.map_or("na".to_string(), |v| format!("{v:.digits$}"))
}

/// Runs this binary's `--child` mode on one phase, optionally with a
/// working-memory limit in MiB.
fn our_side(raw: &Path, label: u8, limit_mib: Option<u64>) -> Result<Side, String> {
    our_side_with(raw, label, limit_mib, None)
}

/// [`our_side`], optionally on a rayon pool of `threads`.
fn our_side_with(
    raw: &Path,
    label: u8,
    limit_mib: Option<u64>,
    threads: Option<usize>,
) -> Result<Side, String> {
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let limit = limit_mib.map_or("0".to_string(), |m| m.to_string());
    let mut cmd = Command::new(exe);
    if let Some(t) = threads {
        cmd.env("RAYON_NUM_THREADS", t.to_string());
    }
    let out = cmd
        .args([
            "analyze",
            "--child",
            &raw.display().to_string(),
            &label.to_string(),
            &limit,
        ])
        .output()
        .map_err(|e| e.to_string())?;
    if !out.status.success() {
        return Err(format!(
            "child failed: {}",
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let field =
        |k: &str| json_number(&text, k).ok_or_else(|| format!("child output lacks {k}: {text}"));
    Ok(Side {
        seconds: field("seconds")?,
        cpu: field("cpu_seconds")?,
        peak_mib: field("peak_mib")?,
        extra: field("slabs")?,
        mean: field("mean")?,
        median: field("median")?,
        max: field("max")?,
    })
}

/// `--child RAW LABEL LIMIT_MIB` (0: the default limit): loads the labels, measures one phase, prints JSON.
fn child(args: &[String]) -> Result<(), String> {
    let [raw, label, limit] = args else {
        return Err("usage: analyze --child RAW LABEL LIMIT_MIB".into());
    };
    let label: u8 = label.parse().map_err(|e| format!("{e}"))?;
    let limit: u64 = limit.parse().map_err(|e| format!("{e}"))?;
    let labels = std::fs::read(raw).map_err(|e| e.to_string())?;
    let opts = ThicknessOptions {
        measure_solid: label == 2,
        measure_pore: label == 1,
        ..Default::default()
    };
    let opts = ThicknessOptions {
        memory_limit: if limit > 0 {
            limit << 20
        } else {
            opts.memory_limit
        },
        ..opts
    };
    let voxel = 2.0 / N as f64;
    let cpu0 = cpu_seconds();
    let t = Instant::now();
    let r = thickness_of_labels(&labels, [N; 3], voxel, &opts).map_err(|e| e.to_string())?;
    let seconds = t.elapsed().as_secs_f64();
    let cpu = cpu_seconds() - cpu0;
    let phase = if label == 2 { &r.solid } else { &r.pore };
    let PhaseThickness::Measured(s) = phase else {
        return Err(format!("phase {label}: {phase:?}"));
    };
    println!(
        "{{\"seconds\": {seconds}, \"cpu_seconds\": {cpu}, \"peak_mib\": {}, \"mean\": {}, \"median\": {}, \"max\": {}, \
         \"voxels\": {}, \"slabs\": {}}}",
        peak_mib(),
        s.mean / voxel,
        s.median / voxel,
        s.max / voxel,
        s.voxels,
        r.slabs
    );
    Ok(())
}

/// CPU seconds (user + system) of this process so far, from
/// /proc/self/stat (fields 14 and 15, in ticks of 1/100 s).
fn cpu_seconds() -> f64 {
    let s = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let rest = s.rsplit_once(") ").map(|(_, r)| r).unwrap_or("");
    rest.split(' ')
        .skip(11)
        .take(2)
        .filter_map(|v| v.parse::<f64>().ok())
        .sum::<f64>()
        / 100.0
}

/// Peak resident memory of this process (VmHWM), MiB.
fn peak_mib() -> f64 {
    let s = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    s.lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map_or(f64::NAN, |kib| kib / 1024.0)
}

/// The number after `"key":` in a one-line JSON object.
fn json_number(text: &str, key: &str) -> Option<f64> {
    let at = text.find(&format!("\"{key}\":"))? + key.len() + 3;
    let rest = text[at..].trim_start();
    let end = rest.find([',', '}']).unwrap_or(rest.len());
    rest[..end].trim().parse().ok()
}

/// The Python with PoreSpy: `MICROFREP_PORESPY_PYTHON`, or the venv under
/// target/, created on first use when the registry is reachable.
fn porespy_python(dir: &Path) -> Option<PathBuf> {
    let spec = microfrep_testsupport::pyvenv::PythonSpec {
        override_var: "MICROFREP_PORESPY_PYTHON",
        venv: Path::new("target/porespy-venv"),
        check: "import porespy",
        packages: &["porespy"],
        log: &dir.join("porespy-install.log"),
    };
    microfrep_testsupport::pyvenv::python_with(&spec)
        .map_err(|e| {
            eprintln!("bench/run analyze: PoreSpy not available ({e}); its columns read na")
        })
        .ok()
}

/// Runs bench/porespy_thickness.py on one phase.
fn their_side(py: &Path, raw: &Path, label: u8) -> Result<Side, String> {
    let n = N.to_string();
    let out = Command::new(py)
        .arg("bench/porespy_thickness.py")
        .arg(raw)
        .args([&n, &n, &n, &label.to_string()])
        .output()
        .map_err(|e| e.to_string())?;
    let text = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        return Err(String::from_utf8_lossy(&out.stderr).into_owned());
    }
    let field =
        |k: &str| json_number(&text, k).ok_or_else(|| format!("PoreSpy output lacks {k}: {text}"));
    Ok(Side {
        seconds: field("seconds")?,
        cpu: field("cpu_seconds")?,
        peak_mib: field("peak_mib")?,
        extra: field("before_mib")?,
        mean: field("mean")?,
        median: field("median")?,
        max: field("max")?,
    })
}
