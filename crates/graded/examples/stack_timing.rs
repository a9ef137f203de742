//! Cost of a material stack against a plain binary slice stack of the same
//! grid (the core slicer, `microfrep-fab`, 1-bit PNGs).
//!
//! `cargo run --release -p microfrep-graded --example stack_timing -- [SIDE] [LAYERS]`
//! (default 512 x 512 voxels, 100 layers) prints three times:
//! the binary stack; the material stack fed by evaluating the part and
//! three fraction expressions per voxel (what a host does); and the
//! material stack from precomputed fractions (dithering and writing alone),
//! each with its ratio to the binary stack, and dithering alone. With
//! `TIMING_ORDERED=1` the material stacks use ordered dithering instead of
//! error diffusion.

use microfrep_core::{BatchEval, Expr, Tape};
use microfrep_fab::grid::SliceGrid;
use microfrep_fab::stack::{write_stack, Format};
use microfrep_graded::depth::Reference;
use microfrep_graded::dmf;
use microfrep_graded::stack::{write_material_stack, MaterialStack, Palette, StackGrid};
use microfrep_graded::subspace::{MaterialModel, Subspace};
use microfrep_shapes as prims;
use rayon::prelude::*;
use std::time::Instant;

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("SIDE and LAYERS are integers"))
        .collect();
    let side = args.first().copied().unwrap_or(512);
    let layers = args.get(1).copied().unwrap_or(100);
    let (min, max) = (
        [-1.0; 3],
        [1.0, 1.0, -1.0 + 2.0 * layers as f64 / side as f64],
    );
    let pitch = 2.0 / side as f64;

    // A ball graded from a ceramic shell to a metal core, and a third
    // material in a noisy band.
    let p = Expr::xyz();
    let part = prims::sphere(&p, &prims::v3([0.0; 3]), 0.98);
    let r = (p[0].square() + p[1].square() + p[2].square()).sqrt();
    let depth = Reference::Distance(0.98 - &r).depth();
    let mut model = MaterialModel::new(3, 0).unwrap();
    let core = Subspace::below_surface(
        &depth,
        0.1,
        0.4,
        [p[0].clone(), p[1].clone()],
        dmf::bias(&Expr::z(), 0.7),
        1,
    );
    model.push(core).unwrap();
    let band = Subspace::new(
        &p[0] - 0.3,
        p.clone(),
        dmf::noise_modulated(&Expr::constant(0.4), &p, 0.3, 6.0, 1),
        2,
    )
    .with_base(1);
    model.push(band).unwrap();
    let mut outs = vec![part.clone()];
    outs.extend(model.fractions(&part));
    let tape = Tape::with_outputs(&outs);
    let geo = microfrep_core::Shape::new(part.clone());

    let dir = std::env::temp_dir().join(format!("stack-timing-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();

    let sg = SliceGrid::new(min, max, pitch, pitch).unwrap();
    let t = Instant::now();
    write_stack(
        &geo,
        &sg,
        &Format::Png { aa: false },
        &dir.join("binary"),
        &|| {},
    )
    .unwrap();
    let binary = t.elapsed().as_secs_f64();

    let grid = StackGrid::new(min, max, [pitch, pitch], pitch).unwrap();
    assert_eq!((grid.nx, grid.ny, grid.layers), (sg.nx, sg.ny, sg.layers));
    let palette = Palette::parse("ceramic=#FFFFFF,metal=#808080,soft=#FF0000").unwrap();
    let mut opts = MaterialStack::new(palette);
    if std::env::var("TIMING_ORDERED").is_ok() {
        opts.method = microfrep_graded::dither::Method::Ordered;
    }
    let (nx, n) = (grid.nx, 3);
    let fill = |k: usize, frac: &mut [f32], inside: &mut [bool]| {
        let z = grid.z(k) as f32;
        frac.par_chunks_mut(nx * n)
            .zip(inside.par_chunks_mut(nx))
            .enumerate()
            .for_each_init(
                || (BatchEval::new(&tape), vec![0.0f32; nx]),
                |(ev, v), (j, (f, m))| {
                    let xs: Vec<f32> = (0..nx).map(|i| grid.x(i) as f32).collect();
                    let ys = vec![grid.y(j) as f32; nx];
                    let zs = vec![z; nx];
                    for o in 0..4 {
                        for c in (0..nx).step_by(microfrep_core::BLOCK) {
                            let e = (c + microfrep_core::BLOCK).min(nx);
                            ev.eval_output(o, &xs[c..e], &ys[c..e], &zs[c..e], &mut v[c..e]);
                        }
                        for i in 0..nx {
                            if o == 0 {
                                m[i] = v[i] >= 0.0;
                            } else {
                                f[i * n + o - 1] = v[i];
                            }
                        }
                    }
                },
            );
    };
    let t = Instant::now();
    let mut src = fill;
    let r1 =
        write_material_stack(&dir.join("evaluated"), &grid, &opts, &mut src, &|_, _| {}).unwrap();
    let evaluated = t.elapsed().as_secs_f64();

    // Precompute every layer's input, then time dithering and writing only.
    let plane = grid.nx * grid.ny;
    let mut pre: Vec<(Vec<f32>, Vec<bool>)> = Vec::with_capacity(grid.layers);
    for k in 0..grid.layers {
        let (mut f, mut m) = (vec![0.0f32; plane * n], vec![false; plane]);
        fill(k, &mut f, &mut m);
        pre.push((f, m));
    }
    let t = Instant::now();
    let mut src = |k: usize, f: &mut [f32], m: &mut [bool]| {
        f.copy_from_slice(&pre[k].0);
        m.copy_from_slice(&pre[k].1);
    };
    let r2 =
        write_material_stack(&dir.join("dithered"), &grid, &opts, &mut src, &|_, _| {}).unwrap();
    let dithered = t.elapsed().as_secs_f64();
    assert_eq!(r1.dither.counts, r2.dither.counts);

    // Dithering alone, no images.
    let t = Instant::now();
    let layout = microfrep_graded::dither::Layout {
        nx: grid.nx,
        ny: grid.ny,
        layers: grid.layers,
        materials: n,
    };
    microfrep_graded::dither::dither(
        layout,
        opts.method,
        opts.memory_limit,
        &mut src,
        &mut |_, _| Ok(()),
        &|_, _| {},
    )
    .unwrap();
    let dither_only = t.elapsed().as_secs_f64();

    let threads = rayon::current_num_threads();
    println!(
        "grid {} x {} x {} ({} voxels, {} inside), {threads} threads",
        grid.nx,
        grid.ny,
        grid.layers,
        grid.voxels(),
        r1.dither.inside
    );
    println!("binary 1-bit stack (fab):          {binary:.3} s");
    println!(
        "material stack, evaluated:         {evaluated:.3} s  ({:.2}x)",
        evaluated / binary
    );
    println!(
        "material stack, dither+write only: {dithered:.3} s  ({:.2}x)",
        dithered / binary
    );
    println!(
        "dithering alone (no images):       {dither_only:.3} s  ({:.2}x)",
        dither_only / binary
    );
    println!(
        "voxels per material {:?}, integrals {:?}",
        r1.dither.counts,
        r1.dither
            .integrals
            .iter()
            .map(|v| v.round())
            .collect::<Vec<_>>()
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
