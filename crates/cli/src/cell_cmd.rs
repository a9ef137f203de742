//! `microfrep cell`: checks a unit cell before replication (Fryazinov et
//! al. Eqs. 4-6) and says which replicating function is safe on each axis.

use crate::model;
use anyhow::{Context, Result};
use clap::Args;
use microfrep_structures::cell_report::{cell_report, AxisReport, CellReport};

#[derive(Args)]
pub struct CellArgs {
    /// Model: a HyperFun file (.hf) or a built-in example name.
    model: String,
    /// The unit cell's box: xmin,ymin,zmin,xmax,ymax,zmax.
    #[arg(long = "box", allow_hyphen_values = true)]
    cell_box: String,
    /// Absolute tolerance for comparing function values.
    #[arg(long, default_value_t = 1e-6)]
    tolerance: f64,
    /// Samples per face edge (2 to 128); symmetry uses this many per axis.
    #[arg(long, default_value_t = 17)]
    samples: usize,
    /// Print the report as JSON.
    #[arg(long)]
    json: bool,
    /// HyperFun object to check (default `my_model`, else the first).
    #[arg(long)]
    object: Option<String>,
    /// HyperFun parameter a[K] = V, as K=V (repeatable).
    #[arg(short = 'a', long = "param", value_parser = model::parse_param)]
    params: Vec<(usize, f64)>,
}

const AXES: [&str; 3] = ["x", "y", "z"];

/// One line of advice for an axis.
fn advice(a: &AxisReport) -> String {
    let saw = if a.sawtooth_safe() {
        "sawtooth safe (full connectivity: continuous field)"
    } else if a.sawtooth_connected() {
        "sawtooth: boundaries match at cell faces but the field jumps there (geometric connectivity only; offsets and blends may crack)"
    } else {
        "sawtooth unsafe (the shape differs on opposite faces: seams)"
    };
    let tri = if a.triangle_safe() {
        "triangle safe (symmetric)"
    } else {
        "triangle mirrors every second cell (not symmetric)"
    };
    format!("{saw}; {tri}")
}

fn yes(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "no"
    }
}

fn axes_where(r: &CellReport, f: impl Fn(&AxisReport) -> bool) -> Vec<&'static str> {
    (0..3).filter(|&i| f(&r.axes[i])).map(|i| AXES[i]).collect()
}

fn to_json(r: &CellReport, min: [f64; 3], max: [f64; 3]) -> serde_json::Value {
    let axes: Vec<serde_json::Value> = (0..3)
        .map(|i| {
            let a = &r.axes[i];
            serde_json::json!({
                "axis": AXES[i],
                "geometric": a.geometric,
                "full": a.full,
                "symmetric": a.symmetric,
                "max_face_diff": a.max_face_diff,
                "max_symmetry_diff": a.max_symmetry_diff,
                "sawtooth_safe": a.sawtooth_safe(),
                "sawtooth_connected": a.sawtooth_connected(),
                "triangle_safe": a.triangle_safe(),
            })
        })
        .collect();
    serde_json::json!({
        "box": [min, max],
        "samples": r.n,
        "tolerance": r.tol,
        "geometric": r.geometric(),
        "full": r.full(),
        "symmetric": r.symmetric(),
        "sawtooth_safe_axes": axes_where(r, AxisReport::sawtooth_safe),
        "triangle_safe_axes": axes_where(r, AxisReport::triangle_safe),
        "axes": axes,
    })
}

pub fn run(a: CellArgs) -> Result<()> {
    let (min, max) = crate::boxarg::parse_box("--box", &a.cell_box)?;
    let opts = model::Options {
        object: a.object.clone(),
        params: a.params.clone(),
    };
    let m = model::load_with(&a.model, &opts)?;
    let r = cell_report(&m.expr, min, max, a.samples, a.tolerance)
        .with_context(|| format!("checking the unit cell of {}", a.model))?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&to_json(&r, min, max))?);
        return Ok(());
    }
    println!(
        "unit cell {min:?}..{max:?}: {n}x{n} samples per face, {n} per axis for symmetry, \
         absolute tolerance {t:e}",
        n = r.n,
        t = r.tol
    );
    println!("axis  geometric  full  symmetric  max face diff  max symmetry diff");
    for (i, ax) in r.axes.iter().enumerate() {
        println!(
            "{:<5} {:<10} {:<5} {:<10} {:<14.3e} {:.3e}",
            AXES[i],
            yes(ax.geometric),
            yes(ax.full),
            yes(ax.symmetric),
            ax.max_face_diff,
            ax.max_symmetry_diff
        );
    }
    for (i, ax) in r.axes.iter().enumerate() {
        println!("{}: {}", AXES[i], advice(ax));
    }
    let list = |v: Vec<&str>| {
        if v.is_empty() {
            "none".to_string()
        } else {
            v.join(" ")
        }
    };
    println!(
        "connectivity: geometric {}, full {}; symmetric {}",
        yes(r.geometric()),
        yes(r.full()),
        yes(r.symmetric())
    );
    println!(
        "safe replication: sawtooth on {}; triangle on {}",
        list(axes_where(&r, AxisReport::sawtooth_safe)),
        list(axes_where(&r, AxisReport::triangle_safe))
    );
    Ok(())
}
