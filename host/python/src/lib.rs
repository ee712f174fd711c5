//! `rtk._rtk`: the native half of the `rtk` Python module. The Python half
//! (`python/rtk/__init__.py`) turns keyword arguments and dictionaries into
//! the scene format and wraps the progress bar; everything that touches a
//! scene, an image or a ray is here, through `rtk_host::embed`, the code
//! the `rtk` binary runs.
//!
//! Why rays and outputs are handled as they are: inputs are read in place
//! from NumPy's buffers (f32 or f64, C-contiguous, no copy), outputs are
//! Rust vectors handed to NumPy without a copy (`IntoPyArray`), and the GIL
//! is released while rendering or tracing, so a 1M-ray trace allocates its
//! outputs and nothing else, and other Python threads run meanwhile.

use numpy::{
    IntoPyArray, PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyKeyboardInterrupt, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rtk_host::embed::{self, EmbeddedScene, HitArrays, RayRec, RenderRequest, SceneSource};
use rtk_shell::file::AttachedArray;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::RecvTimeoutError;
use std::time::Duration;

/// rtk's message (file, line, column, object, key) as a Python exception.
fn err(e: anyhow::Error) -> PyErr {
    PyValueError::new_err(format!("{e:#}"))
}

/// A built scene: render it, cast rays at it, read what it holds.
#[pyclass(module = "rtk._rtk")]
struct Scene {
    inner: EmbeddedScene,
}

/// Plugin folders: `plugin_path`, then `RTK_PLUGIN_PATH`, then the wheel's.
fn plugin_path(extra: Vec<PathBuf>, bundled: Option<PathBuf>) -> rtk_shell::PluginPath {
    embed::plugin_path(&extra, bundled.as_deref())
}

/// Build a scene from its source, the GIL released (aggregates build in parallel).
fn build(py: Python<'_>, source: SceneSource, path: rtk_shell::PluginPath) -> PyResult<Scene> {
    let inner = py
        .detach(|| EmbeddedScene::build(source, path))
        .map_err(err)?;
    Ok(Scene { inner })
}

/// Load a scene file (TOML, or a .ply/.obj mesh under `accel`) with `--set`
/// overrides.
#[pyfunction]
#[pyo3(signature = (path, sets, accel=None, plugin_path=vec![], bundled=None))]
fn load_file(
    py: Python<'_>,
    path: PathBuf,
    sets: Vec<String>,
    accel: Option<String>,
    plugin_path: Vec<PathBuf>,
    bundled: Option<PathBuf>,
) -> PyResult<Scene> {
    let mut source = SceneSource::from_file(&path, accel.as_deref()).map_err(err)?;
    source.set(&sets);
    build(py, source, self::plugin_path(plugin_path, bundled))
}

/// One array a dictionary scene attaches to a definition.
type Attachment<'py> = (String, String, Bound<'py, PyAny>);

/// Load scene text; `arrays` are (definition, parameter, array) triples
/// handed to the definitions' `create` by pointer.
#[pyfunction]
#[pyo3(signature = (text, base_dir, name, sets, arrays=vec![], plugin_path=vec![], bundled=None))]
#[allow(clippy::too_many_arguments)]
fn load_string(
    py: Python<'_>,
    text: String,
    base_dir: PathBuf,
    name: String,
    sets: Vec<String>,
    arrays: Vec<Attachment<'_>>,
    plugin_path: Vec<PathBuf>,
    bundled: Option<PathBuf>,
) -> PyResult<Scene> {
    let mut source = SceneSource::from_text(text, &base_dir, &name).map_err(err)?;
    for (def, param, array) in arrays {
        source.attach(&def, attached(&param, &array)?);
    }
    source.set(&sets);
    build(py, source, self::plugin_path(plugin_path, bundled))
}

/// A NumPy array as a bulk array: 2-D, C-contiguous, of a type the
/// kernel's `bulk_dtype` names (the Python half converts the rest).
fn attached(name: &str, a: &Bound<'_, PyAny>) -> PyResult<AttachedArray> {
    use rtk_kernel::abi::bulk_dtype as d;
    let bad = || PyValueError::new_err(format!("{name}: expected a 2-D NumPy array"));
    let arr = a.cast::<numpy::PyUntypedArray>().map_err(|_| bad())?;
    if arr.ndim() != 2 {
        return Err(PyValueError::new_err(format!(
            "{name}: expected a 2-D array (rows x columns), got {} dimensions",
            arr.ndim()
        )));
    }
    let (rows, cols) = (arr.shape()[0] as u64, arr.shape()[1] as u64);
    macro_rules! bytes_of {
        ($t:ty, $code:expr) => {
            if let Ok(x) = a.extract::<PyReadonlyArray2<'_, $t>>() {
                let s = x.as_slice().map_err(|_| {
                    PyValueError::new_err(format!("{name}: the array must be C-contiguous"))
                })?;
                let data = s.iter().flat_map(|v| v.to_ne_bytes()).collect();
                return Ok(AttachedArray {
                    name: name.into(),
                    dtype: $code,
                    rows,
                    cols,
                    data,
                });
            }
        };
    }
    bytes_of!(f32, d::F32);
    bytes_of!(f64, d::F64);
    bytes_of!(i32, d::I32);
    bytes_of!(u32, d::U32);
    bytes_of!(i64, d::I64);
    bytes_of!(u8, d::U8);
    Err(PyValueError::new_err(format!(
        "{name}: unsupported element type {} (use float32/float64 or int32/uint32/int64)",
        arr.dtype()
    )))
}

/// Rays read in place from NumPy: N x 3 origins and directions of one float type.
enum RayArrays<'a> {
    F32(&'a [f32], &'a [f32]),
    F64(&'a [f64], &'a [f64]),
}

/// `t_min`/`t_max`: one value for every ray, or one per ray.
#[inline(always)]
fn per_ray(v: &[f32], i: usize) -> f32 {
    if v.len() == 1 {
        v[0]
    } else {
        v[i]
    }
}

#[pymethods]
impl Scene {
    /// Image width and height.
    #[getter]
    fn size(&self) -> (u32, u32) {
        let r = &self.inner.world().desc.render;
        (r.width, r.height)
    }

    /// Samples per pixel the scene asks for.
    #[getter]
    fn spp(&self) -> u32 {
        self.inner.world().desc.render.spp
    }

    /// Each instance's path, by the id `trace` reports as `object`.
    fn objects(&self) -> Vec<String> {
        self.inner.instances().to_vec()
    }

    /// The build's record as JSON text (the Python half parses it).
    fn stats_json(&self) -> String {
        let w = self.inner.world();
        let t = &w.timings;
        let prepare: serde_json::Map<String, serde_json::Value> = t
            .prepare_by_class
            .iter()
            .map(|(c, d)| (c.clone(), d.as_secs_f64().into()))
            .collect();
        serde_json::json!({
            "width": w.desc.render.width,
            "height": w.desc.render.height,
            "spp": w.desc.render.spp,
            "root_class": w.root.class_name(),
            "bounds": [w.bounds.min.to_array(), w.bounds.max.to_array()],
            "plugins": w.plugins.iter().map(|p| serde_json::json!({
                "class": p.class, "kind": p.kind.name(), "file": p.path.display().to_string(),
            })).collect::<Vec<_>>(),
            "objects_created": w.objects_created,
            "instances": w.instances.len(),
            "shaders": w.shaders.len(),
            "lights": w.lights.len(),
            "files_read": w.files_read,
            "seconds": {
                "create": t.create.as_secs_f64(),
                "prepare": t.prepare.as_secs_f64(),
                "prepare_by_class": prepare,
            },
        })
        .to_string()
    }

    /// Render; returns (H x W x 3 float32 array, interrupted). `progress`
    /// is called as `progress(done_spp, spp)` between passes. Ctrl-C stops
    /// the render and raises KeyboardInterrupt.
    #[pyo3(signature = (spp=None, seed=None, threads=None, progress=None))]
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        spp: Option<u32>,
        seed: Option<u64>,
        threads: Option<usize>,
        progress: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (stop, done) = (AtomicBool::new(false), AtomicU64::new(0));
        let req = RenderRequest {
            spp,
            seed,
            threads,
            stop: &stop,
            done: &done,
        };
        let inner = &mut self.inner;
        let (tx, rx) = std::sync::mpsc::channel();
        // Borrowed by the GIL-free wait, which must be `Send`.
        let rx = std::sync::Mutex::new(rx);
        let total = spp.unwrap_or(inner.world().desc.render.spp) as u64;
        let mut interrupted_by_user = None;
        let result = std::thread::scope(|s| {
            s.spawn(|| {
                let _ = tx.send(inner.render(&req));
            });
            loop {
                // Wait without the GIL, then let Python see its signals.
                let got = py.detach(|| match rx.lock() {
                    Ok(rx) => rx.recv_timeout(Duration::from_millis(50)),
                    Err(_) => Err(RecvTimeoutError::Disconnected),
                });
                match got {
                    Ok(r) => break r,
                    Err(RecvTimeoutError::Disconnected) => {
                        break Err(anyhow::anyhow!(
                            "the rendering thread stopped without an image"
                        ))
                    }
                    Err(RecvTimeoutError::Timeout) => {}
                }
                if let Err(e) = py.check_signals() {
                    stop.store(true, Ordering::SeqCst);
                    interrupted_by_user = Some(e);
                }
                if let Some(cb) = &progress {
                    if interrupted_by_user.is_none() {
                        if let Err(e) = cb.call1((done.load(Ordering::Relaxed), total)) {
                            stop.store(true, Ordering::SeqCst);
                            interrupted_by_user = Some(e);
                        }
                    }
                }
            }
        });
        if let Some(e) = interrupted_by_user {
            return Err(e);
        }
        let img = result.map_err(err)?;
        if let Some(cb) = &progress {
            cb.call1((total, total))?;
        }
        if img.interrupted {
            return Err(PyKeyboardInterrupt::new_err("rendering was stopped"));
        }
        let (w, h) = (img.width as usize, img.height as usize);
        let arr = img.rgb.into_pyarray(py).reshape([h, w, 3])?;
        Ok(arr.into_any())
    }

    /// Cast N rays: `origins`/`directions` N x 3 C-contiguous float32 or
    /// float64 (one type), `t_min`/`t_max` float32 of length 1 or N.
    /// Returns (t, prim, bary, hit, object, normal, uv); the last three
    /// are None unless `surface`.
    #[pyo3(signature = (origins, directions, t_min, t_max, occluded=false, threads=None, surface=true))]
    #[allow(clippy::too_many_arguments)]
    fn trace<'py>(
        &self,
        py: Python<'py>,
        origins: Bound<'py, PyAny>,
        directions: Bound<'py, PyAny>,
        t_min: PyReadonlyArray1<'py, f32>,
        t_max: PyReadonlyArray1<'py, f32>,
        occluded: bool,
        threads: Option<usize>,
        surface: bool,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (o32, d32, o64, d64);
        let rays = if let (Ok(o), Ok(d)) = (
            origins.extract::<PyReadonlyArray2<'py, f32>>(),
            directions.extract::<PyReadonlyArray2<'py, f32>>(),
        ) {
            (o32, d32) = (o, d);
            RayArrays::F32(
                contiguous(&o32, "origins")?,
                contiguous(&d32, "directions")?,
            )
        } else if let (Ok(o), Ok(d)) = (
            origins.extract::<PyReadonlyArray2<'py, f64>>(),
            directions.extract::<PyReadonlyArray2<'py, f64>>(),
        ) {
            (o64, d64) = (o, d);
            RayArrays::F64(
                contiguous(&o64, "origins")?,
                contiguous(&d64, "directions")?,
            )
        } else {
            return Err(PyValueError::new_err(
                "origins and directions must be N x 3 arrays of one float type (float32 or float64)",
            ));
        };
        let n = match rays {
            RayArrays::F32(o, d) => check_shapes(o.len(), d.len())?,
            RayArrays::F64(o, d) => check_shapes(o.len(), d.len())?,
        };
        let (tmin, tmax) = (t_min.as_slice()?, t_max.as_slice()?);
        for (name, v) in [("t_min", tmin), ("t_max", tmax)] {
            if v.len() != 1 && v.len() != n {
                return Err(PyValueError::new_err(format!(
                    "{name} must be one number or one per ray ({n}), got {}",
                    v.len()
                )));
            }
        }
        let m = if surface { n } else { 0 };
        let mut out = Outputs::new(n, m);
        let inner = &self.inner;
        // One closure per element type, so each inlines into the tracing loop.
        let traced = match rays {
            RayArrays::F32(o, d) => {
                let ray = |i: usize| RayRec {
                    o: [o[3 * i], o[3 * i + 1], o[3 * i + 2]],
                    d: [d[3 * i], d[3 * i + 1], d[3 * i + 2]],
                    t_min: per_ray(tmin, i),
                    t_max: per_ray(tmax, i),
                };
                py.detach(|| inner.trace(n, &ray, occluded, threads, out.arrays()))
            }
            RayArrays::F64(o, d) => {
                let ray = |i: usize| RayRec {
                    o: [o[3 * i] as f32, o[3 * i + 1] as f32, o[3 * i + 2] as f32],
                    d: [d[3 * i] as f32, d[3 * i + 1] as f32, d[3 * i + 2] as f32],
                    t_min: per_ray(tmin, i),
                    t_max: per_ray(tmax, i),
                };
                py.detach(|| inner.trace(n, &ray, occluded, threads, out.arrays()))
            }
        };
        traced.map_err(err)?;
        out.into_dict(py, surface)
    }
}

/// A C-contiguous array's elements.
fn contiguous<'a, T: numpy::Element>(
    a: &'a PyReadonlyArray2<'_, T>,
    name: &str,
) -> PyResult<&'a [T]> {
    if a.shape()[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "{name} must be N x 3, got {} x {}",
            a.shape()[0],
            a.shape()[1]
        )));
    }
    a.as_slice()
        .map_err(|_| PyValueError::new_err(format!("{name} must be C-contiguous")))
}

/// The ray count, if origins and directions agree.
fn check_shapes(o: usize, d: usize) -> PyResult<usize> {
    if o != d {
        return Err(PyValueError::new_err(format!(
            "origins ({} rays) and directions ({} rays) differ in length",
            o / 3,
            d / 3
        )));
    }
    Ok(o / 3)
}

/// The trace outputs, owned until handed to NumPy.
struct Outputs {
    t: Vec<f32>,
    prim: Vec<i64>,
    bary: Vec<[f32; 2]>,
    hit: Vec<bool>,
    object: Vec<i64>,
    normal: Vec<[f32; 3]>,
    uv: Vec<[f32; 2]>,
}

impl Outputs {
    /// `n` rays; `m` surface records (n or 0).
    fn new(n: usize, m: usize) -> Outputs {
        Outputs {
            t: vec![0.0; n],
            prim: vec![0; n],
            bary: vec![[0.0; 2]; n],
            hit: vec![false; n],
            object: vec![0; m],
            normal: vec![[0.0; 3]; m],
            uv: vec![[0.0; 2]; m],
        }
    }

    fn arrays(&mut self) -> HitArrays<'_> {
        HitArrays {
            t: &mut self.t,
            prim: &mut self.prim,
            bary: &mut self.bary,
            hit: &mut self.hit,
            object: &mut self.object,
            normal: &mut self.normal,
            uv: &mut self.uv,
        }
    }

    fn into_dict(self, py: Python<'_>, surface: bool) -> PyResult<Bound<'_, PyDict>> {
        let n = self.t.len();
        let d = PyDict::new(py);
        d.set_item("t", self.t.into_pyarray(py))?;
        d.set_item("prim", self.prim.into_pyarray(py))?;
        d.set_item(
            "bary",
            self.bary
                .into_flattened()
                .into_pyarray(py)
                .reshape([n, 2])?,
        )?;
        d.set_item("hit", self.hit.into_pyarray(py))?;
        if surface {
            d.set_item("object", self.object.into_pyarray(py))?;
            d.set_item(
                "normal",
                self.normal
                    .into_flattened()
                    .into_pyarray(py)
                    .reshape([n, 3])?,
            )?;
            d.set_item(
                "uv",
                self.uv.into_flattened().into_pyarray(py).reshape([n, 2])?,
            )?;
        }
        Ok(d)
    }
}

/// Every plugin on the path: (class, kind, version, file); a refused
/// library has kind "refused" and the reason as its version.
#[pyfunction]
#[pyo3(signature = (plugin_path=vec![], bundled=None))]
fn plugins(
    plugin_path: Vec<PathBuf>,
    bundled: Option<PathBuf>,
) -> Vec<(String, String, String, String)> {
    embed::list_plugins(&self::plugin_path(plugin_path, bundled))
        .into_iter()
        .map(|(c, k, v, f)| (c, k, v, f.display().to_string()))
        .collect()
}

/// Write an H x W x 3 float32 image to PNG (sRGB) or EXR (linear).
#[pyfunction]
fn write(path: PathBuf, image: PyReadonlyArray1<'_, f32>, width: u32, height: u32) -> PyResult<()> {
    embed::write_image(&path, width, height, image.as_slice()?).map_err(err)
}

/// An image file as (width, height, flat float32 RGB).
#[pyfunction]
fn read_image(py: Python<'_>, path: PathBuf) -> PyResult<(u32, u32, Bound<'_, PyArray1<f32>>)> {
    let (w, h, data) = embed::read_image(&path).map_err(err)?;
    Ok((w, h, data.into_pyarray(py)))
}

/// `rtk diff`'s (RMSE, relMSE) of two flat float32 RGB images.
#[pyfunction]
fn image_error(a: PyReadonlyArray1<'_, f32>, b: PyReadonlyArray1<'_, f32>) -> PyResult<(f64, f64)> {
    embed::image_error(a.as_slice()?, b.as_slice()?).map_err(err)
}

/// Run an `rtk` command line in this process (`converge` and friends), the
/// GIL released; its output goes to this process's stdout and stderr.
#[pyfunction]
fn run_command(py: Python<'_>, args: Vec<String>) -> PyResult<()> {
    py.detach(|| embed::run_command(&args))
        .map_err(|e| PyRuntimeError::new_err(format!("{e:#}")))
}

/// The native module.
#[pymodule]
fn _rtk(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Scene>()?;
    m.add_function(wrap_pyfunction!(load_file, m)?)?;
    m.add_function(wrap_pyfunction!(load_string, m)?)?;
    m.add_function(wrap_pyfunction!(plugins, m)?)?;
    m.add_function(wrap_pyfunction!(write, m)?)?;
    m.add_function(wrap_pyfunction!(read_image, m)?)?;
    m.add_function(wrap_pyfunction!(image_error, m)?)?;
    m.add_function(wrap_pyfunction!(run_command, m)?)?;
    Ok(())
}
