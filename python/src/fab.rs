//! Meshes, slice stacks, renders and analysis of a shape.

use crate::errors;
use crate::model::{check_box, PyShape};
use microfrep::analysis::summary::to_json;
use microfrep::analysis::{analyze as run_analyze, AnalyzeOptions, Grid};
use microfrep::fab::stack::StackFormat;
use microfrep::fab::{write_stack, Format, SliceGrid};
use microfrep::io::{AtomicDir, AtomicFile};
use microfrep::mesh::job::{mesh_to_file, JobOptions, Tolerance};
use microfrep::mesh::{CellMethod, MeshOptions, Plan};
use microfrep::render::{cutaway, ray_cast, section, Camera, Plane, RgbImage, View};
use numpy::{IntoPyArray, PyArray2, PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::{Path, PathBuf};

type Box3 = ([f64; 3], [f64; 3]);
/// A mesh as NumPy arrays: vertices (N x 3) and faces (M x 3).
type MeshArrays<'py> = (Bound<'py, PyArray2<f32>>, Bound<'py, PyArray2<u32>>);
/// A slice grid: layers, nx, ny, min and max corners.
type GridInfo = (usize, usize, usize, [f64; 3], [f64; 3]);

fn cells(name: &str) -> PyResult<CellMethod> {
    match name {
        "cubes" => Ok(CellMethod::Cubes),
        "tets" => Ok(CellMethod::Tetrahedra),
        _ => Err(errors::input(format!("cells '{name}': cubes or tets"))),
    }
}

/// A stack format by name, as `microfrep slice --format` (and `--aa`).
pub fn format(name: &str, aa: bool) -> PyResult<Format> {
    match (name, aa) {
        ("png", aa) => Ok(Format::Png { aa }),
        (_, true) => Err(errors::input("aa applies to format 'png' only")),
        ("svg", false) => Ok(Format::Svg),
        ("cli", false) => Ok(Format::Cli),
        _ => Err(errors::input(format!("format '{name}': png, svg or cli"))),
    }
}

/// The slice grid of a box, layer thickness and pixel size.
pub fn slice_grid(b: Box3, layer: f64, pixel: f64) -> PyResult<SliceGrid> {
    check_box(b.0, b.1)?;
    SliceGrid::new(b.0, b.1, layer, pixel).map_err(errors::fab)
}

/// The analysis grid of a box: `resolution` voxels on its longest side,
/// or voxels of side `voxel`; 256 on the longest side by default.
pub fn analysis_grid(b: Box3, resolution: Option<usize>, voxel: Option<f64>) -> PyResult<Grid> {
    check_box(b.0, b.1)?;
    let g = match (resolution, voxel) {
        (Some(_), Some(_)) => {
            return Err(errors::input("give resolution or voxel, not both"));
        }
        (Some(n), None) => Grid::new([b.0, b.1], n),
        (None, Some(v)) => Grid::with_voxel([b.0, b.1], v),
        (None, None) => Grid::new([b.0, b.1], 256),
    };
    g.map_err(errors::analysis)
}

fn view(name: &str) -> PyResult<View> {
    name.parse::<View>().map_err(errors::render)
}

#[pymethods]
impl PyShape {
    /// A closed triangle mesh: (vertices N x 3 float32, faces M x 3
    /// uint32), triangles counter-clockwise seen from outside.
    #[pyo3(signature = (resolution=256, bounds=None, cells="cubes"))]
    fn mesh<'py>(
        &self,
        py: Python<'py>,
        resolution: usize,
        bounds: Option<Box3>,
        cells: &str,
    ) -> PyResult<MeshArrays<'py>> {
        let b = self.frame(py, bounds)?;
        let mut opts = MeshOptions::new(b.corners(), resolution);
        opts.cells = self::cells(cells)?;
        let shape = self.s.clone();
        let limit = errors::memory_limit();
        let (v, t) = py.allow_threads(move || {
            let plan = Plan::new(&shape, &opts).map_err(errors::mesh)?;
            let est = microfrep::mesh::memory::estimate(&plan);
            if est.bytes > limit {
                return Err(errors::check_memory(est.bytes, "the mesh").unwrap_err());
            }
            let m = plan.run(&|_| {}).map_err(errors::mesh)?;
            let v: Vec<f32> = m.vertices.iter().flatten().copied().collect();
            let t: Vec<u32> = m.triangles.iter().flatten().copied().collect();
            Ok::<_, PyErr>((v, t))
        })?;
        let (nv, nt) = (v.len() / 3, t.len() / 3);
        let reshape = |e: PyErr| errors::input(e.to_string());
        Ok((
            v.into_pyarray(py).reshape([nv, 3]).map_err(reshape)?,
            t.into_pyarray(py).reshape([nt, 3]).map_err(reshape)?,
        ))
    }

    /// Meshes into a file (format by extension: .stl .obj .ply .3mf), as
    /// `microfrep mesh`; returns the summary as JSON text, the keys of
    /// `microfrep mesh --json`. `tolerance` (cells) or `tolerance_mm`
    /// merges flat regions as `--tolerance` does.
    #[pyo3(signature = (path, resolution=256, bounds=None, cells="cubes", stream=false, sharp=false, tolerance=None, tolerance_mm=None))]
    #[allow(clippy::too_many_arguments)]
    fn mesh_to_file(
        &self,
        py: Python<'_>,
        path: PathBuf,
        resolution: usize,
        bounds: Option<Box3>,
        cells: &str,
        stream: bool,
        sharp: bool,
        tolerance: Option<f64>,
        tolerance_mm: Option<f64>,
    ) -> PyResult<String> {
        let start = std::time::Instant::now();
        microfrep::mesh::write::format_of(&path).map_err(errors::mesh)?;
        let b = self.frame(py, bounds)?;
        let mut opts = MeshOptions::new(b.corners(), resolution);
        opts.cells = self::cells(cells)?;
        if sharp && opts.cells != CellMethod::Cubes {
            return Err(errors::input(
                "sharp features are placed in marching cubes: use cells='cubes'",
            ));
        }
        opts.sharp = sharp;
        let tolerance = match (tolerance, tolerance_mm) {
            (Some(_), Some(_)) => {
                return Err(errors::input(
                    "give tolerance (cells) or tolerance_mm, not both",
                ))
            }
            (Some(c), None) => Some(Tolerance::Cells(c)),
            (None, Some(u)) => Some(Tolerance::Units(u)),
            (None, None) => None,
        };
        let job = JobOptions {
            stream,
            tolerance,
            ..JobOptions::default()
        };
        let shape = self.s.clone();
        let s = py
            .allow_threads(|| mesh_to_file(&shape, &opts, &path, &job, &|_, _| {}))
            .map_err(errors::mesh)?;
        let peak = microfrep::io::limits::peak_rss().unwrap_or(f64::NAN);
        let j = microfrep::mesh::report::to_json(
            &s,
            &path.display().to_string(),
            start.elapsed().as_secs_f64(),
            peak,
        );
        Ok(j.to_string())
    }

    /// The slice grid this shape gets: (layers, nx, ny, min corner).
    #[pyo3(signature = (layer, pixel, bounds=None))]
    fn slice_grid(
        &self,
        py: Python<'_>,
        layer: f64,
        pixel: f64,
        bounds: Option<Box3>,
    ) -> PyResult<GridInfo> {
        let b = self.frame(py, bounds)?;
        let g = slice_grid((b.min, b.max), layer, pixel)?;
        Ok((g.layers, g.nx, g.ny, b.min, b.max))
    }

    /// Layers `k0..k1` as a (k1 - k0) x ny x nx uint8 array: 255 inside,
    /// 0 outside (or 8-bit coverage with `aa`), row 0 at the largest y, as
    /// in the PNG files.
    #[pyo3(signature = (layer, pixel, bounds=None, aa=false, k0=0, k1=None))]
    #[allow(clippy::too_many_arguments)]
    fn slice_array<'py>(
        &self,
        py: Python<'py>,
        layer: f64,
        pixel: f64,
        bounds: Option<Box3>,
        aa: bool,
        k0: usize,
        k1: Option<usize>,
    ) -> PyResult<Bound<'py, PyArray3<u8>>> {
        let b = self.frame(py, bounds)?;
        let g = slice_grid((b.min, b.max), layer, pixel)?;
        let k1 = k1.unwrap_or(g.layers);
        if !(k0 < k1 && k1 <= g.layers) {
            return Err(errors::input(format!(
                "layers {k0}..{k1} are not a range in 0..{}",
                g.layers
            )));
        }
        let (nx, ny) = (g.nx, g.ny);
        errors::check_memory(
            ((k1 - k0) * nx * ny) as f64,
            &format!("{} layers of {nx} x {ny} pixels", k1 - k0),
        )?;
        let shape = self.s.clone();
        let data = py.allow_threads(|| {
            let mut data = vec![0u8; (k1 - k0) * nx * ny];
            data.par_chunks_mut(nx * ny)
                .enumerate()
                .for_each(|(i, img)| {
                    let l = microfrep::fab::rasterize(&shape, &g, k0 + i);
                    let pixels = if aa {
                        let cov = microfrep::fab::coverage::coverage(
                            &shape,
                            &l,
                            g.pixel,
                            [g.min[0], g.min[1]],
                        );
                        microfrep::fab::image::GreyImage::from_coverage(nx, ny, &cov).pixels
                    } else {
                        microfrep::fab::image::GreyImage::binary(&l).pixels
                    };
                    img.copy_from_slice(&pixels);
                });
            data
        });
        data.into_pyarray(py)
            .reshape([k1 - k0, ny, nx])
            .map_err(|e| errors::input(e.to_string()))
    }

    /// Writes the stack as `microfrep slice` does (atomically); returns the
    /// summary as JSON text.
    #[pyo3(signature = (path, layer, pixel, bounds=None, format="png", aa=false))]
    #[allow(clippy::too_many_arguments)]
    fn slice_to(
        &self,
        py: Python<'_>,
        path: PathBuf,
        layer: f64,
        pixel: f64,
        bounds: Option<Box3>,
        format: &str,
        aa: bool,
    ) -> PyResult<String> {
        let f = self::format(format, aa)?;
        if f == Format::Cli && path.extension().and_then(|e| e.to_str()) != Some("cli") {
            return Err(errors::input(format!(
                "{}: a CLI slice file takes the extension .cli",
                path.display()
            )));
        }
        let b = self.frame(py, bounds)?;
        let g = slice_grid((b.min, b.max), layer, pixel)?;
        let shape = self.s.clone();
        py.allow_threads(|| write_stack(&shape, &g, &f, &path, &|| {}))
            .map_err(errors::fab)?;
        let census = census(&self.s, &g);
        Ok(serde_json::json!({
            "output": path.display().to_string(),
            "layers": g.layers,
            "image_size": [g.nx, g.ny],
            "bounds": [b.min, b.max],
            "runtime_errors": census,
        })
        .to_string())
    }

    /// The bytes of layers `k0..k1` of a stack (PNG or SVG files, or CLI
    /// layer blocks), as `microfrep slice` writes them; `out` names the
    /// stack in errors.
    #[pyo3(signature = (format, aa, bounds, layer, pixel, k0, k1, out))]
    #[allow(clippy::too_many_arguments)]
    fn slice_layer_bytes<'py>(
        &self,
        py: Python<'py>,
        format: &str,
        aa: bool,
        bounds: Box3,
        layer: f64,
        pixel: f64,
        k0: usize,
        k1: usize,
        out: PathBuf,
    ) -> PyResult<Vec<Bound<'py, PyBytes>>> {
        let f = self::format(format, aa)?;
        let g = slice_grid(bounds, layer, pixel)?;
        if !(k0 < k1 && k1 <= g.layers) {
            return Err(errors::input(format!(
                "layers {k0}..{k1} are not a range in 0..{}",
                g.layers
            )));
        }
        let shape = self.s.clone();
        let bytes: Vec<Vec<u8>> = py.allow_threads(|| {
            (k0..k1)
                .into_par_iter()
                .map(|k| {
                    f.layer(&shape, &g, k, &out.join(f.layer_name(k)))
                        .map(|(b, _)| b)
                })
                .collect::<Result<Vec<_>, _>>()
                .map_err(errors::fab)
        })?;
        Ok(bytes.iter().map(|b| PyBytes::new(py, b)).collect())
    }

    /// Run-time errors of the model at the pixel centres of layers
    /// `k0..k1` of a stack (None: the model has no error channel).
    #[pyo3(signature = (bounds, layer, pixel, k0=0, k1=None))]
    fn slice_census(
        &self,
        py: Python<'_>,
        bounds: Box3,
        layer: f64,
        pixel: f64,
        k0: usize,
        k1: Option<usize>,
    ) -> PyResult<Option<u64>> {
        let g = slice_grid(bounds, layer, pixel)?;
        let k1 = k1.unwrap_or(g.layers).min(g.layers);
        let s = self.s.clone();
        Ok(py.allow_threads(|| census_of(&s, &g, k0, k1)))
    }

    /// A ray-cast image (height x width x 3, uint8), a cut-away, or a
    /// section of the value on the plane `section = (axis, value)`.
    #[pyo3(signature = (width=1024, height=768, view="iso", bounds=None, cutaway=false, section=None))]
    #[allow(clippy::too_many_arguments)]
    fn render<'py>(
        &self,
        py: Python<'py>,
        width: usize,
        height: usize,
        view: &str,
        bounds: Option<Box3>,
        cutaway: bool,
        section: Option<(usize, f64)>,
    ) -> PyResult<Bound<'py, PyArray3<u8>>> {
        let img = self.render_image(py, width, height, view, bounds, cutaway, section)?;
        img.data
            .into_pyarray(py)
            .reshape([img.height, img.width, 3])
            .map_err(|e| errors::input(e.to_string()))
    }

    /// The same image as `render` gives, as the bytes of a PNG file (the
    /// encoder of `microfrep render`).
    #[pyo3(signature = (width=256, height=256, view="iso", bounds=None, cutaway=false, section=None))]
    #[allow(clippy::too_many_arguments)]
    fn render_png<'py>(
        &self,
        py: Python<'py>,
        width: usize,
        height: usize,
        view: &str,
        bounds: Option<Box3>,
        cutaway: bool,
        section: Option<(usize, f64)>,
    ) -> PyResult<Bound<'py, PyBytes>> {
        let img = self.render_image(py, width, height, view, bounds, cutaway, section)?;
        let png = py
            .allow_threads(|| img.encode_png())
            .map_err(errors::render)?;
        Ok(PyBytes::new(py, &png))
    }

    /// The analysis of `microfrep analyze`, as its JSON text.
    #[pyo3(signature = (resolution=None, voxel=None, bounds=None, region=None, connectivity=true, thickness=true, name=None, region_name=None))]
    #[allow(clippy::too_many_arguments)]
    fn analyze(
        &self,
        py: Python<'_>,
        resolution: Option<usize>,
        voxel: Option<f64>,
        bounds: Option<Box3>,
        region: Option<PyShape>,
        connectivity: bool,
        thickness: bool,
        name: Option<String>,
        region_name: Option<String>,
    ) -> PyResult<String> {
        let b = self.frame(py, bounds)?;
        let grid = analysis_grid((b.min, b.max), resolution, voxel)?;
        let mut opts = AnalyzeOptions {
            connectivity,
            thickness,
            ..AnalyzeOptions::default()
        };
        opts.memory_limit = errors::memory_limit() as u64;
        opts.thickness_options.memory_limit = opts.memory_limit;
        let shape = self.s.clone();
        let rs = region.as_ref().map(|r| r.s.clone());
        let report = py
            .allow_threads(|| run_analyze(&shape, rs.as_ref(), grid, &opts, &|_, _, _| {}))
            .map_err(errors::analysis)?;
        let name = name.unwrap_or_else(|| self.name.clone());
        let rn = region_name.or_else(|| region.map(|r| r.name));
        Ok(to_json(&report, &name, rn.as_deref()).to_string())
    }
}

/// Run-time errors at the pixel centres (None: the model has no error
/// channel).
fn census(shape: &microfrep::Shape, g: &SliceGrid) -> Option<u64> {
    census_of(shape, g, 0, g.layers)
}

fn census_of(shape: &microfrep::Shape, g: &SliceGrid, k0: usize, k1: usize) -> Option<u64> {
    let xs: Vec<f64> = (0..g.nx).map(|i| g.x(i)).collect();
    let ys: Vec<f64> = (0..g.ny).map(|j| g.y(j)).collect();
    let zs: Vec<f64> = (k0..k1).map(|k| g.z(k)).collect();
    shape.error_census(&xs, &ys, &zs).map(|c| c.errors)
}

enum Target {
    File(AtomicFile),
    Dir(AtomicDir),
}

/// Assembles a slice stack from layers computed elsewhere, in any order,
/// into the same files `microfrep slice` writes: under a temporary name
/// next to the output, renamed when [`StackWriter::commit`] is called
/// after the last layer (dropped unfinished, the temporary is removed).
#[pyclass(module = "microfrep._core", unsendable)]
pub struct StackWriter {
    target: Option<Target>,
    format: Format,
    grid: SliceGrid,
    out: PathBuf,
    /// Layers written (a directory), or the next layer to append (a file).
    done: Vec<bool>,
    next: usize,
    pending: BTreeMap<usize, Vec<u8>>,
}

#[pymethods]
impl StackWriter {
    #[new]
    #[pyo3(signature = (path, format, aa, bounds, layer, pixel))]
    fn new(
        path: PathBuf,
        format: &str,
        aa: bool,
        bounds: Box3,
        layer: f64,
        pixel: f64,
    ) -> PyResult<StackWriter> {
        let f = self::format(format, aa)?;
        let grid = slice_grid(bounds, layer, pixel)?;
        let target = if f.single_file() {
            let mut file = AtomicFile::create(&path).map_err(errors::io)?;
            file.write_all(&f.header(&grid))
                .map_err(|e| errors::io(file.err(e)))?;
            Target::File(file)
        } else {
            Target::Dir(AtomicDir::create(&path).map_err(errors::io)?)
        };
        Ok(StackWriter {
            target: Some(target),
            format: f,
            done: vec![false; grid.layers],
            grid,
            out: path,
            next: 0,
            pending: BTreeMap::new(),
        })
    }

    /// Layers in the stack.
    #[getter]
    fn layers(&self) -> usize {
        self.grid.layers
    }

    /// Adds layer `k`'s bytes.
    fn write(&mut self, k: usize, data: Vec<u8>) -> PyResult<()> {
        if k >= self.grid.layers || self.done[k] {
            return Err(errors::input(format!(
                "layer {k}: not in 0..{} or written already",
                self.grid.layers
            )));
        }
        self.done[k] = true;
        let name = self.format.layer_name(k);
        match self.target.as_mut() {
            None => Err(errors::input("the stack is closed")),
            Some(Target::Dir(d)) => d.write(&name, &data).map_err(errors::io),
            Some(Target::File(f)) => {
                self.pending.insert(k, data);
                while let Some(b) = self.pending.remove(&self.next) {
                    f.write_all(&b).map_err(|e| errors::io(f.err(e)))?;
                    self.next += 1;
                }
                Ok(())
            }
        }
    }

    /// Writes the manifest (or trailer) and renames the stack into place.
    fn commit(&mut self) -> PyResult<String> {
        if let Some(k) = self.done.iter().position(|d| !d) {
            return Err(errors::input(format!(
                "layer {k} of {} is missing",
                self.grid.layers
            )));
        }
        let tail = self.format.footer(&self.grid);
        match self.target.take() {
            None => return Err(errors::input("the stack is closed")),
            Some(Target::File(mut f)) => {
                f.write_all(&tail).map_err(|e| errors::io(f.err(e)))?;
                f.commit().map_err(errors::io)?;
            }
            Some(Target::Dir(d)) => {
                d.write("manifest.json", &tail).map_err(errors::io)?;
                d.commit().map_err(errors::io)?;
            }
        }
        Ok(self.out.display().to_string())
    }

    /// Drops the unfinished stack (its temporary is removed).
    fn abort(&mut self) {
        self.target = None;
    }
}

/// Whether `path` could be a stack output (not an input of this process).
#[allow(dead_code)]
fn check_output(path: &Path) -> PyResult<()> {
    microfrep::io::atomic::check_not_input(path).map_err(errors::io)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<StackWriter>()?;
    Ok(())
}

impl PyShape {
    /// The image of `render` and `render_png`, computed with the GIL
    /// released.
    #[allow(clippy::too_many_arguments)]
    fn render_image(
        &self,
        py: Python<'_>,
        width: usize,
        height: usize,
        view: &str,
        bounds: Option<Box3>,
        cutaway: bool,
        section: Option<(usize, f64)>,
    ) -> PyResult<RgbImage> {
        microfrep::render::camera::check_size(width, height).map_err(errors::render)?;
        let v = self::view(view)?;
        let b = self.frame(py, bounds)?;
        let (min, max) = (b.min, b.max);
        let shape = self.s.clone();
        Ok(match section {
            Some(_) if cutaway => return Err(errors::input("section and cutaway do not combine")),
            Some((axis, value)) => {
                if axis > 2 {
                    return Err(errors::input(format!("section axis {axis}: 0, 1 or 2")));
                }
                if !(min[axis]..=max[axis]).contains(&value) {
                    return Err(errors::input(format!(
                        "section {value}: the plane is outside the box ({} .. {} on that axis)",
                        min[axis], max[axis]
                    )));
                }
                py.allow_threads(|| {
                    self::section(&shape, Plane { axis, value }, min, max, width, height)
                })
            }
            None => py.allow_threads(|| {
                let s = if cutaway {
                    self::cutaway(&shape, v, min, max)
                } else {
                    shape
                };
                ray_cast(&s, &Camera::fit(v, min, max, width, height), min, max)
            }),
        })
    }
}
