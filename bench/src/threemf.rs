//! `bench/run 3mf`: file sizes and write times of 3MF extensions against
//! STL. (a) an octet lattice filling a 50 mm cube (2 mm cells, 0.2 mm
//! struts) as a beam-lattice 3MF against the STL of the part meshed at
//! 0.05 mm — measured on an 8 mm block at 0.05 mm and extrapolated by volume
//! to the cube, and cross-checked from the whole cube meshed at 0.4 mm
//! scaled by (0.4 / 0.05)^2 — plus the volume of the solid re-built from the
//! file's graph against the lattice FRep's; (b) a slice stack of the block
//! against its STL; (c) a graded two-material cube as volumetric data against
//! STL iso-surface shells of the mixing ratio.

use microfrep_3mf::beam::{BeamLattice, ClipMode};
use microfrep_3mf::slice::SliceStack;
use microfrep_3mf::volumetric::*;
use microfrep_3mf::{
    lattices, read_from, write_to, Base, BaseMaterials, Mesh, MeshResolution, Model, Polygon,
    Transform, Unit, WriteOptions,
};
use microfrep_core::{Expr, Shape};
use microfrep_fab::{layer_polygons, rasterize, SliceGrid};
use microfrep_mesh::check::volume_area;
use microfrep_mesh::{Mesh as TriMesh, MeshOptions, Plan};
use microfrep_structures::strut_graph::StrutGraph;
use microfrep_structures::struts::{strut_lattice, StrutLattice};
use std::time::Instant;

const STL_BYTES_PER_TRIANGLE: f64 = 50.0;

fn boxed(e: &Expr, lo: [f64; 3], hi: [f64; 3]) -> Expr {
    let [x, y, z] = Expr::xyz();
    let c = [&x, &y, &z];
    let mut r = e.clone();
    for a in 0..3 {
        r = r.min(c[a] - lo[a]).min(hi[a] - c[a]);
    }
    r
}

fn mesh(e: &Expr, lo: [f64; 3], hi: [f64; 3], voxel: f64) -> Result<TriMesh, String> {
    let pad = 2.0 * voxel;
    let b = [lo.map(|v| v - pad), hi.map(|v| v + pad)];
    let n = ((b[1][0] - b[0][0]) / voxel).round() as usize;
    Plan::new(&Shape::from(e), &MeshOptions::new(b, n))
        .and_then(|p| p.run(&|_| {}))
        .map_err(|e| e.to_string())
}

fn cube_mesh(s: f64) -> Mesh {
    Mesh::cuboid([0.0; 3], [s; 3])
}

fn write_model(m: &Model) -> Result<(Vec<u8>, f64), String> {
    let t = Instant::now();
    let bytes = write_to(
        std::io::Cursor::new(Vec::new()),
        m,
        &WriteOptions::default(),
    )
    .map_err(|e| e.to_string())?
    .into_inner();
    Ok((bytes, t.elapsed().as_secs_f64()))
}

/// Seconds to write a binary STL of `m` into memory.
fn stl_write_s(m: &TriMesh) -> f64 {
    use std::io::Write;
    let t = Instant::now();
    let mut out = Vec::with_capacity(84 + 50 * m.triangles.len());
    out.extend_from_slice(&[0u8; 80]);
    out.extend_from_slice(&(m.triangles.len() as u32).to_le_bytes());
    for tri in &m.triangles {
        out.extend_from_slice(&[0u8; 12]);
        for &i in tri {
            for c in m.vertices[i as usize] {
                out.write_all(&c.to_le_bytes()).unwrap();
            }
        }
        out.extend_from_slice(&[0u8; 2]);
    }
    std::hint::black_box(&out);
    t.elapsed().as_secs_f64()
}

fn lattice_3mf(g: &StrutGraph, side: f64) -> Model {
    let mut m = Model::new(Unit::Millimeter);
    let clip = m.add_mesh(Some("clip"), cube_mesh(side));
    let mut l = BeamLattice::new(g.radii.first().map_or(0.2, |r| r[0]), 1e-4);
    for (&(a, b), r) in g.beams.iter().zip(&g.radii) {
        l.push(a, b, r[0], r[1]);
    }
    l.clipping = Some((ClipMode::Inside, clip));
    let id = m.add_mesh(
        Some("octet lattice"),
        Mesh {
            vertices: g.nodes.clone(),
            beam_lattice: Some(l),
            ..Mesh::default()
        },
    );
    m.add_item(id, Transform::IDENTITY);
    m
}

fn graph_of(model: &Model) -> Result<StrutGraph, String> {
    let l = lattices(model).map_err(|e| e.to_string())?;
    let l = l.first().ok_or("no lattice read back")?;
    Ok(StrutGraph {
        nodes: l.nodes.clone(),
        beams: l.beams.iter().map(|b| (b.v1, b.v2)).collect(),
        radii: l.beams.iter().map(|b| [b.r1, b.r2]).collect(),
    })
}

pub fn run() -> Result<(), String> {
    let (side, cell, r) = (50.0, 2.0, 0.2);
    let (lo, hi) = ([0.0; 3], [side; 3]);
    // (a) Beam lattice.
    let t = Instant::now();
    let g =
        StrutGraph::tile(StrutLattice::Octet, lo, hi, cell, |_| r).map_err(|e| e.to_string())?;
    let tile_s = t.elapsed().as_secs_f64();
    let model = lattice_3mf(&g, side);
    let (bytes, write_s) = write_model(&model)?;
    let t = Instant::now();
    let back = read_from(std::io::Cursor::new(bytes.clone())).map_err(|e| e.to_string())?;
    let read_s = t.elapsed().as_secs_f64();
    let back_graph = graph_of(&back)?;
    if back_graph.beams.len() != g.beams.len() {
        return Err("beam count changed in the round trip".into());
    }
    // STL at 0.05 mm on an 8 mm block (4 cells a side), by volume to the cube.
    let block = 8.0;
    let (blo, bhi) = ([0.0; 3], [block; 3]);
    let frep = boxed(
        &strut_lattice(StrutLattice::Octet, &Expr::xyz(), cell, r),
        blo,
        bhi,
    );
    let t = Instant::now();
    let m_frep = mesh(&frep, blo, bhi, 0.05)?;
    let mesh_s = t.elapsed().as_secs_f64();
    let sub = g.clip_box(blo, bhi);
    let from_file = boxed(
        &graph_of(&lattice_3mf_read(&sub, block)?)?
            .expr()
            .map_err(|e| e.to_string())?,
        blo,
        bhi,
    );
    let m_file = mesh(&from_file, blo, bhi, 0.05)?;
    let (v_frep, _) = volume_area(&m_frep);
    let (v_file, _) = volume_area(&m_file);
    let vol_err = (v_file - v_frep).abs() / v_frep;
    let scale = (side / block).powi(3);
    let tri_block = m_frep.triangles.len() as f64;
    let stl_005 = (84.0 + STL_BYTES_PER_TRIANGLE * tri_block * scale) as u64;
    let stl_write_005 = stl_write_s(&m_frep) * scale;
    // Cross-check: the whole cube at 0.4 mm, triangles scaled by (0.4/0.05)^2.
    let whole = boxed(&back_graph.expr().map_err(|e| e.to_string())?, lo, hi);
    let t = Instant::now();
    let m_coarse = mesh(&whole, lo, hi, 0.4)?;
    let coarse_s = t.elapsed().as_secs_f64();
    let stl_005_b = (84.0 + STL_BYTES_PER_TRIANGLE * m_coarse.triangles.len() as f64 * 64.0) as u64;
    println!(
        "RESULT beam_lattice beams={} nodes={} threemf_bytes={} threemf_write_s={write_s:.3} read_s={read_s:.3} tile_s={tile_s:.3} \
         stl_bytes_est={stl_005} stl_write_s_est={stl_write_005:.2} ratio={:.0} \
         block_triangles_0.05mm={} block_mesh_s={mesh_s:.1} coarse_triangles_0.4mm={} coarse_mesh_s={coarse_s:.1} \
         stl_bytes_est_from_coarse={stl_005_b} ratio_from_coarse={:.0} volume_frep={v_frep:.4} volume_from_file={v_file:.4} volume_rel_err={vol_err:.2e}",
        g.beams.len(),
        g.nodes.len(),
        bytes.len(),
        stl_005 as f64 / bytes.len() as f64,
        m_frep.triangles.len(),
        m_coarse.triangles.len(),
        stl_005_b as f64 / bytes.len() as f64,
    );
    if vol_err > 0.01 {
        return Err(format!(
            "volume from the file's graph differs by {vol_err:.2e} (> 1 %)"
        ));
    }

    // (b) Slice stack of the block, 0.05 mm layers, 0.025 mm pixels.
    let tape = Shape::new(from_file.clone());
    let grid = SliceGrid::new(blo, bhi, 0.05, 0.025).map_err(|e| e.to_string())?;
    let t = Instant::now();
    let layers: Vec<Vec<Polygon>> = (0..grid.layers)
        .map(|k| layer_polygons(&tape, &grid, &rasterize(&tape, &grid, k)))
        .collect();
    let slice_s = t.elapsed().as_secs_f64();
    let polys: usize = layers.iter().map(Vec::len).sum();
    let mut m = Model::new(Unit::Millimeter);
    let low = m.add_mesh(Some("block"), cube_mesh(block));
    let sid = m.next_id();
    m.slice_stacks
        .push(SliceStack::uniform(sid, 0.0, 0.05, layers));
    m.objects[0].slice_stack = Some(sid);
    m.objects[0].mesh_resolution = MeshResolution::Low;
    m.add_item(low, Transform::IDENTITY);
    let (sbytes, swrite_s) = write_model(&m)?;
    let stl_block = 84 + 50 * m_file.triangles.len();
    println!(
        "RESULT slice_stack layers={} polygons={polys} threemf_bytes={} threemf_write_s={swrite_s:.3} slice_s={slice_s:.1} \
         stl_bytes={stl_block} stl_write_s={:.3} ratio={:.1}",
        grid.layers,
        sbytes.len(),
        stl_write_s(&m_file),
        stl_block as f64 / sbytes.len() as f64
    );

    // (c) Graded two-material cube: mixing ratio = radial gradient.
    let ratio = |p: [f64; 3]| {
        let d = ((p[0] - 25.0).powi(2) + (p[1] - 25.0).powi(2) + (p[2] - 25.0).powi(2)).sqrt();
        (d / 43.3).clamp(0.0, 1.0)
    };
    let n = 128;
    let t = Instant::now();
    let im = Image3D::from_fn(3, [n; 3], PixelLayout::YA, 8, |x, y, z| {
        let p = [x, y, z].map(|i| (i as f64 + 0.5) / n as f64 * side);
        let v = ratio(p);
        [v, v, v, 1.0 - v]
    })
    .map_err(|e| e.to_string())?;
    let mut m = Model::new(Unit::Millimeter);
    m.base_materials.push(BaseMaterials {
        id: 1,
        bases: vec![
            Base {
                name: "A".into(),
                color: [200, 30, 30, 255],
            },
            Base {
                name: "B".into(),
                color: [30, 30, 200, 255],
            },
        ],
    });
    m.images.push(im);
    m.image_functions.push(FunctionFromImage3D::new(4, 3));
    let tu = Transform::box_to_unit(lo, hi);
    m.volume_data.push(VolumeData {
        id: 5,
        composite: Some(Composite {
            base_materials: 1,
            mappings: vec![
                FunctionRef::new(4, "red", tu),
                FunctionRef::new(4, "alpha", tu),
            ],
        }),
        ..VolumeData::default()
    });
    let mut cm = cube_mesh(side);
    cm.volume_id = Some(5);
    let id = m.add_mesh(Some("graded cube"), cm);
    m.add_item(id, Transform::IDENTITY);
    let (vbytes, vwrite_s) = write_model(&m)?;
    let vol_s = t.elapsed().as_secs_f64();
    // STL baseline: the part split into 16 material bins, shells at the 15
    // bin boundaries (iso-surfaces of the ratio) meshed at 0.4 mm, plus the cube.
    let [x, y, z] = Expr::xyz();
    let d = ((&x - 25.0).square() + (&y - 25.0).square() + (&z - 25.0).square()).sqrt() / 43.3;
    let mut tris = 12usize;
    let t = Instant::now();
    for k in 1..16 {
        let shell = boxed(&(k as f64 / 16.0 - &d), lo, hi);
        tris += mesh(&shell, lo, hi, 0.4)?.triangles.len();
    }
    let bins_s = t.elapsed().as_secs_f64();
    let stl_bins = 84 * 16 + 50 * tris;
    println!(
        "RESULT volumetric image=128^3x2ch8bit threemf_bytes={} threemf_write_s={vwrite_s:.3} build_s={vol_s:.2} \
         stl_16_bins_bytes={stl_bins} stl_bins_triangles={tris} stl_bins_mesh_s={bins_s:.1} ratio={:.1}",
        vbytes.len(),
        stl_bins as f64 / vbytes.len() as f64
    );
    Ok(())
}

/// The block's lattice through a 3MF file and back.
fn lattice_3mf_read(g: &StrutGraph, side: f64) -> Result<Model, String> {
    let (bytes, _) = write_model(&lattice_3mf(g, side))?;
    read_from(std::io::Cursor::new(bytes)).map_err(|e| e.to_string())
}
