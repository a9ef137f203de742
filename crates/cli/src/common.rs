//! What every verb shares: the model options (`MODEL`, `--object`, `-a`,
//! `--field`, `--bounds`), the run options (`--quiet`, `--json`,
//! `--threads`), loading with progress, the one rule for the default box,
//! progress bars and error chains.

use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use microfrep::{load, Bounds, LoadError, LoadOptions, Loaded};
use std::io::IsTerminal;
use std::path::Path;

/// The model a verb works on.
#[derive(Args, Clone, Debug)]
pub struct ModelArgs {
    /// Model: a HyperFun file (.hf), a mesh (.stl .obj .ply .3mf), a scan
    /// (.nrrd .nii .nii.gz .tif .raw, or a folder of slices;
    /// FILE:iso=V[,smooth=MM,spacing=X,Y,Z,step=N,series=UID,frame=F]; its
    /// coordinates are in the file's frame, LPS for DICOM and RAS for
    /// NIfTI, or frame=lps|ras|voxel), or a built-in example (see
    /// `microfrep examples`).
    pub model: String,
    /// HyperFun object to evaluate (default `my_model`, else the first).
    #[arg(long)]
    pub object: Option<String>,
    /// HyperFun parameter a[K] = V, as K=V (repeatable).
    #[arg(short = 'a', long = "param", value_parser = parse_param)]
    pub params: Vec<(usize, f64)>,
    /// A mesh, scan or CSV bound as the HyperFun function NAME(x):
    /// NAME=FILE[:key=value,...], e.g. bone=femur.stl or ct=scan.nrrd:iso=300 (repeatable).
    #[arg(long = "field", value_parser = parse_field)]
    pub fields: Vec<(String, String)>,
    /// Box xmin,ymin,zmin,xmax,ymax,zmax (default: the model's own: a
    /// built-in example's box, a mesh's or scan's extent, else what
    /// interval analysis proves).
    #[arg(long, allow_hyphen_values = true)]
    pub bounds: Option<String>,
}

/// How a verb runs and reports.
#[derive(Args, Clone, Debug)]
pub struct RunArgs {
    /// No progress bars and no summary.
    #[arg(long)]
    pub quiet: bool,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
}

impl RunArgs {
    /// Sizes the global thread pool.
    pub fn init(&self) -> Result<()> {
        if let Some(n) = self.threads {
            if n == 0 || n > 1024 {
                bail!("--threads {n}: give 1 to 1024");
            }
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build_global()
                .context("setting up the thread pool")?;
        }
        Ok(())
    }

    /// A progress bar on stderr when it is a terminal and not `--quiet`.
    pub fn bar(&self, what: &str) -> ProgressBar {
        let target = if self.quiet || !std::io::stderr().is_terminal() {
            ProgressDrawTarget::hidden()
        } else {
            ProgressDrawTarget::stderr()
        };
        let pb = ProgressBar::with_draw_target(Some(0), target);
        let style = format!("{{msg:20}} {{bar:40}} {{pos}}/{{len}} {what} {{elapsed}}");
        if let Ok(s) = ProgressStyle::with_template(&style) {
            pb.set_style(s);
        }
        pb
    }

    /// Prints a note for the user on stderr (not with `--quiet`).
    pub fn note(&self, s: &str) {
        if !self.quiet {
            eprintln!("note: {s}");
        }
    }
}

/// Parses `K=V` (as given to `-a`/`--param`).
pub fn parse_param(s: &str) -> Result<(usize, f64), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected K=V (e.g. 1=0.5), got '{s}'"))?;
    let k = k
        .trim()
        .parse()
        .map_err(|_| format!("bad parameter index '{k}'"))?;
    let v = v
        .trim()
        .parse()
        .map_err(|_| format!("bad parameter value '{v}'"))?;
    Ok((k, v))
}

/// Parses `NAME=SOURCE` (as given to `--field`).
pub fn parse_field(s: &str) -> Result<(String, String), String> {
    let (n, src) = s
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=FILE[:key=value,...], got '{s}'"))?;
    let n = n.trim();
    let ok = n.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
        && n.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !ok {
        return Err(format!("--field name '{n}' must be a HyperFun identifier"));
    }
    Ok((n.to_string(), src.trim().to_string()))
}

impl ModelArgs {
    /// What the facade's loader takes from these options.
    pub fn load_options(&self) -> LoadOptions {
        LoadOptions {
            object: self.object.clone(),
            params: self.params.clone(),
            fields: self.fields.clone(),
            memory_limit: None,
        }
    }
}

/// Runs `f` with a progress callback `(stage, done, total)` drawn as a
/// bar (hidden with `--quiet` or off a terminal), cleared when it ends.
pub fn with_stages<T>(run: &RunArgs, f: impl FnOnce(load::Progress) -> T) -> T {
    let bar = run.bar("");
    let progress = |stage: &str, done: u64, total: u64| {
        bar.set_message(stage.to_string());
        bar.set_length(total);
        bar.set_position(done);
    };
    let r = f(&progress);
    bar.finish_and_clear();
    r
}

/// Loads the model (with a progress bar for long builds), protects its
/// files from being overwritten, and prints its notes.
pub fn load_model(m: &ModelArgs, run: &RunArgs) -> Result<Loaded> {
    let opts = m.load_options();
    let loaded = with_stages(run, |p| load::load_with_progress(&m.model, &opts, p));
    let loaded = loaded.map_err(|e| match e {
        LoadError::HyperFun(d) => {
            // The whole report with source lines and carets.
            let text = std::fs::read_to_string(&m.model).unwrap_or_default();
            eprint!("{}", d.render(&text));
            anyhow!("{}: {} error(s)", m.model, d.errors().count().max(1))
        }
        e => anyhow::Error::new(e),
    })?;
    for p in &loaded.inputs {
        microfrep::io::atomic::register_input(p);
    }
    for n in &loaded.notes {
        run.note(n);
    }
    Ok(loaded)
}

/// The box to work in: `--bounds`, else the model's own (one rule for
/// every verb, so `mesh` and `slice` of a model frame the same box).
pub fn frame(loaded: &Loaded, m: &ModelArgs, run: &RunArgs) -> Result<Bounds> {
    if let Some(s) = &m.bounds {
        let (lo, hi) = parse_box("--bounds", s)?;
        return Ok(Bounds::new(lo, hi));
    }
    let bar = run.bar("");
    bar.set_message("finding the bounds");
    let opts = microfrep::core::shape::BoundsOptions {
        progress: Some(std::sync::Arc::new({
            let bar = bar.clone();
            move |f: f64| {
                bar.set_length(100);
                bar.set_position((100.0 * f) as u64);
            }
        })),
        ..Default::default()
    };
    let b = loaded.shape.bounds_with(&opts);
    bar.finish_and_clear();
    b.with_context(|| format!("model '{}'", m.model))
}

/// Parses comma-separated numbers for option `flag`, naming the one that
/// is not a number.
pub fn parse_numbers(flag: &str, s: &str) -> Result<Vec<f64>> {
    s.split(',')
        .enumerate()
        .map(|(i, t)| {
            t.trim()
                .parse::<f64>()
                .with_context(|| format!("{flag}: value {} ('{t}') is not a number", i + 1))
        })
        .collect()
}

/// Parses `xmin,ymin,zmin,xmax,ymax,zmax` for option `flag`: six finite
/// numbers with min < max on every axis, within what f32 grids represent.
pub fn parse_box(flag: &str, s: &str) -> Result<([f64; 3], [f64; 3])> {
    let v = parse_numbers(flag, s)?;
    if v.len() != 6 {
        bail!(
            "{flag} needs 6 numbers xmin,ymin,zmin,xmax,ymax,zmax, got {}",
            v.len()
        );
    }
    if let Some(t) = v.iter().find(|t| !t.is_finite()) {
        bail!("{flag}: {t} is not a finite number");
    }
    let max = microfrep::io::precision::MAX_COORDINATE;
    if let Some(t) = v.iter().find(|t| t.abs() > max) {
        bail!("{flag}: {t:e} is beyond what the sampling grids can represent (|v| <= {max:e})");
    }
    let (lo, hi) = ([v[0], v[1], v[2]], [v[3], v[4], v[5]]);
    for (a, name) in ["x", "y", "z"].iter().enumerate() {
        if lo[a] >= hi[a] {
            bail!(
                "{flag}: {name}min {} must be below {name}max {}",
                lo[a],
                hi[a]
            );
        }
    }
    Ok((lo, hi))
}

/// Refuses an output whose extension is not one of `exts` (lower case,
/// without the dot).
pub fn check_extension(out: &Path, exts: &[&str], what: &str) -> Result<()> {
    let e = out
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    if !exts.contains(&e.as_str()) {
        let list: Vec<String> = exts.iter().map(|e| format!(".{e}")).collect();
        bail!("{}: {what} must end in {}", out.display(), list.join(", "));
    }
    Ok(())
}

/// An error and its causes on one line, each cause once: errors that
/// already show their source (an I/O error naming its file) are not
/// followed by the same text again.
pub fn chain(e: &anyhow::Error) -> String {
    let mut msg = e.to_string();
    for c in e.chain().skip(1) {
        let t = c.to_string();
        if !msg.contains(&t) {
            msg.push_str(": ");
            msg.push_str(&t);
        }
    }
    msg
}

/// Fails before any work when a HyperFun loop of the model runs to its
/// iteration limit at one of a few probe points of the box `b` (a model
/// that does not terminate; see [`check_terminates`]).
pub fn probe_terminates(m: &Loaded, b: [[f64; 3]; 2]) -> Result<()> {
    if m.hyperfun.is_some() {
        let mut pe = m.shape.point();
        for p in microfrep::io::precision::probe_points(b[0], b[1], 64) {
            pe.eval(p);
        }
    }
    check_terminates(m, &[])
}

/// Fails when a HyperFun loop of the model ran to its iteration limit at a
/// point the job sampled: from then on every evaluation of the model fails
/// at once, so the values depend on the order of evaluation. `outputs`
/// (written from such values) are removed.
pub fn check_terminates(m: &Loaded, outputs: &[&Path]) -> Result<()> {
    if let Some(e) = m.hyperfun.as_ref().and_then(|h| h.runaway_loop()) {
        for p in outputs {
            let _ = if p.is_dir() {
                std::fs::remove_dir_all(p)
            } else {
                std::fs::remove_file(p)
            };
        }
        let removed = if outputs.is_empty() {
            ""
        } else {
            "; the output was removed"
        };
        bail!(
            "the model does not terminate everywhere: {e}; values sampled before and after \
             it differ{removed}"
        );
    }
    Ok(())
}

/// `v` with 7 significant digits.
pub fn num(v: f64) -> String {
    microfrep::io::text::sig(v, 7)
}
