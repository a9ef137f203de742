//! `microfrep scan-info SCAN[:options]`: what a scan holds before an iso
//! value is chosen: size, spacing, frame, value range, a text histogram and
//! suggested thresholds (Otsu's, and 300 HU for bone when the values look
//! like CT) with the volume each keeps.

use crate::common::{with_stages, RunArgs};
use anyhow::Result;
use clap::Args;
use microfrep::scan::stats::{count_at_or_above, looks_like_ct, Histogram};
use microfrep::scan::Volume;

#[derive(Args)]
pub struct ScanInfoArgs {
    /// The scan: .nrrd .nhdr .nii .nii.gz .hdr .tif .raw, or a folder of
    /// DICOM or TIFF slices, with the reading options
    /// `:frame=file|lps|ras|voxel`, `spacing=X,Y,Z` (mm; needed for TIFF),
    /// `step=N`, `series=UID`.
    scan: String,
    /// Rows of the text histogram.
    #[arg(long, default_value_t = 24)]
    rows: usize,
    #[command(flatten)]
    run: RunArgs,
}

/// One suggested threshold and what it keeps.
struct Suggestion {
    name: &'static str,
    why: &'static str,
    iso: f64,
    voxels: u64,
}

pub fn run(a: ScanInfoArgs) -> Result<()> {
    a.run.init()?;
    if !(2..=200).contains(&a.rows) {
        anyhow::bail!("--rows {}: give 2 to 200", a.rows);
    }
    let (vol, notes) = with_stages(&a.run, |p| microfrep::load::read_scan(&a.scan, None, p))?;
    // Otsu on a fine histogram; the printed one is coarser.
    let fine = Histogram::of(&vol, 1024);
    let shown = Histogram::of(&vol, a.rows);
    let voxel_mm3 = vol.spacing.iter().product::<f64>();
    let mut sugg = Vec::new();
    if let Some(t) = fine.otsu() {
        let t = round_to(t, fine.width());
        sugg.push(Suggestion {
            name: "otsu",
            why: "Otsu's threshold: best split of the histogram in two classes",
            iso: t,
            voxels: count_at_or_above(&vol, t),
        });
    }
    let ct = looks_like_ct(&fine);
    if ct {
        sugg.push(Suggestion {
            name: "bone",
            why: "bone in CT, 300 HU",
            iso: 300.0,
            voxels: count_at_or_above(&vol, 300.0),
        });
    }
    // How to pass a threshold: after the options given, if any.
    let has_options = microfrep::load::Source::parse(&a.scan).is_ok_and(|s| !s.options.is_empty());
    let with_iso = |v: f64| {
        let sep = if has_options { ',' } else { ':' };
        format!("{}{sep}iso={}", a.scan, microfrep::io::text::sig(v, 6))
    };
    if a.run.json {
        let s: Vec<_> = sugg
            .iter()
            .map(|s| {
                serde_json::json!({
                    "name": s.name, "why": s.why, "iso": s.iso, "voxels": s.voxels,
                    "source": with_iso(s.iso),
                    "volume_mm3": s.voxels as f64 * voxel_mm3,
                    "fraction": s.voxels as f64 / vol.len() as f64,
                })
            })
            .collect();
        let j = serde_json::json!({
            "source": vol.source.display().to_string(),
            "dims": vol.dims,
            "spacing_mm": vol.spacing,
            "origin_mm": vol.origin,
            "bounds_mm": vol.bounds(),
            "frame": vol.frame,
            "sample_type": format!("{:?}", vol.samples.sample_type()).to_lowercase(),
            "slope": vol.slope,
            "intercept": vol.intercept,
            "min": finite_or_null(fine.lo),
            "max": finite_or_null(fine.hi),
            "non_finite": fine.non_finite,
            "looks_like_ct": ct,
            "histogram": {
                "lo": finite_or_null(shown.lo), "hi": finite_or_null(shown.hi),
                "counts": shown.counts,
            },
            "suggestions": s,
        });
        println!("{}", serde_json::to_string_pretty(&j)?);
        return Ok(());
    }
    print_text(&vol, &shown, &notes, &sugg, voxel_mm3, ct, &with_iso);
    Ok(())
}

fn finite_or_null(v: f64) -> serde_json::Value {
    if v.is_finite() {
        serde_json::json!(v)
    } else {
        serde_json::Value::Null
    }
}

/// `t` rounded to a short decimal within a tenth of `step`.
fn round_to(t: f64, step: f64) -> f64 {
    if step.is_nan() || step <= 0.0 {
        return t;
    }
    let q = 10f64.powf((step * 0.1).log10().floor());
    (t / q).round() * q
}

fn print_text(
    vol: &Volume,
    h: &Histogram,
    notes: &[String],
    sugg: &[Suggestion],
    voxel_mm3: f64,
    ct: bool,
    with_iso: &dyn Fn(f64) -> String,
) {
    use microfrep::io::text::sig;
    let [nx, ny, nz] = vol.dims;
    let [sx, sy, sz] = vol.spacing;
    println!("scan      {}", vol.source.display());
    println!(
        "size      {nx} x {ny} x {nz} voxels of {} x {} x {} mm ({} samples, {})",
        sig(sx, 4),
        sig(sy, 4),
        sig(sz, 4),
        format!("{:?}", vol.samples.sample_type()).to_lowercase(),
        microfrep::scan::volume::describe_bytes(vol.bytes())
    );
    for n in notes {
        println!("frame     {n}");
    }
    let b = vol.bounds();
    println!(
        "box       x {} .. {}, y {} .. {}, z {} .. {} mm (voxel faces)",
        sig(b[0][0], 5),
        sig(b[1][0], 5),
        sig(b[0][1], 5),
        sig(b[1][1], 5),
        sig(b[0][2], 5),
        sig(b[1][2], 5)
    );
    if h.hi.partial_cmp(&h.lo).is_none_or(|o| o.is_lt()) {
        println!("values    none finite ({} samples)", h.non_finite);
        return;
    }
    println!(
        "values    {} .. {}{}{}",
        sig(h.lo, 6),
        sig(h.hi, 6),
        if vol.slope != 1.0 || vol.intercept != 0.0 {
            format!(
                " (stored x {} + {})",
                sig(vol.slope, 6),
                sig(vol.intercept, 6)
            )
        } else {
            String::new()
        },
        if h.non_finite > 0 {
            format!("; {} samples are not finite", h.non_finite)
        } else {
            String::new()
        }
    );
    if ct {
        println!("          (air near -1000 and values past 300: this looks like CT in Hounsfield units)");
    }
    let total: u64 = h.counts.iter().sum();
    let most = h.counts.iter().copied().max().unwrap_or(1).max(1);
    println!("histogram (bar length: share of the fullest bin)");
    let w = h.width();
    for (b, &c) in h.counts.iter().enumerate() {
        let lo = h.lo + b as f64 * w;
        let bar = "#".repeat(((c as f64 / most as f64) * 40.0).round() as usize);
        let pct = 100.0 * c as f64 / total.max(1) as f64;
        println!(
            "  {:>11} .. {:<11} {:>6.2} %  {bar}",
            sig(lo, 5),
            sig(lo + w, 5),
            pct
        );
    }
    if sugg.is_empty() {
        println!("no threshold to suggest: every finite sample has the same value");
        return;
    }
    println!("suggested iso values (inside is value >= iso; volume of those voxels):");
    for s in sugg {
        println!(
            "  {:<5} {:>10}   {} mm^3, {:.2} % of the voxels   {}   ({})",
            s.name,
            sig(s.iso, 6),
            sig(s.voxels as f64 * voxel_mm3, 6),
            100.0 * s.voxels as f64 / vol.len() as f64,
            with_iso(s.iso),
            s.why
        );
    }
}
