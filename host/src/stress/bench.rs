//! What every stress case needs: sizes, result lines, scenes built from TOML
//! text through the shell, meshes written exactly, a probe that traces
//! through the world's root, and renders through the real render loop.

use crate::render::render_loop::{self, Film};
use crate::render::tracer::Tracer;
use crate::shared::threads::Pool;
use anyhow::{bail, Context, Result};
use rtk_kernel::abi::{geom_mask, Hit, LocalGeom, Ray, TraceCtx};
use rtk_kernel::glam::{DMat3, DVec3, Vec3};
use rtk_kernel::RngState;
use rtk_shell::{Desc, PluginPath, Registry, SceneFile, World};
use std::fmt::{self, Write as _};
use std::path::{Path, PathBuf};

/// How long a run may take.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Size {
    /// Seconds: the default test run.
    Quick,
    /// Minutes: the catalogue's own sizes where they are affordable.
    Full,
}

/// What a measurement must reach.
#[derive(Clone, Copy, Debug)]
pub enum Target {
    /// A count that must be zero.
    Zero,
    /// A rate or error that must not exceed the bound.
    AtMost(f64),
    /// A share that must reach the bound (what a case covers).
    AtLeast(f64),
}

impl fmt::Display for Target {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            Target::Zero => write!(f, "0"),
            Target::AtMost(x) => write!(f, "<= {x:.3e}"),
            Target::AtLeast(x) => write!(f, ">= {x:.3e}"),
        }
    }
}

/// One measurement.
#[derive(Clone, Debug)]
pub struct Line {
    /// The configuration measured (scale, offset, aggregate...).
    pub setup: String,
    /// The metric's name (docs/numerics.md §3).
    pub metric: &'static str,
    /// Its value.
    pub value: f64,
    /// Its target.
    pub target: Target,
}

impl Line {
    /// A measurement.
    pub fn new(setup: impl Into<String>, metric: &'static str, value: f64, target: Target) -> Line {
        Line {
            setup: setup.into(),
            metric,
            value,
            target,
        }
    }

    /// A count that must be zero.
    pub fn count(setup: impl Into<String>, metric: &'static str, n: u64) -> Line {
        Line::new(setup, metric, n as f64, Target::Zero)
    }

    /// Whether the value reaches the target (a NaN never does).
    pub fn pass(&self) -> bool {
        match self.target {
            Target::Zero => self.value == 0.0,
            Target::AtMost(b) => self.value <= b,
            Target::AtLeast(b) => self.value >= b,
        }
    }

    /// The line `rtk stress` prints.
    pub fn row(&self, id: &str) -> String {
        let value = if self.value == self.value.trunc() && self.value.abs() < 1e9 {
            format!("{}", self.value)
        } else {
            format!("{:.3e}", self.value)
        };
        format!(
            "{:<4} {:<44} {:<28} {:>12} {:>10}  {}",
            id,
            self.setup,
            self.metric,
            value,
            self.target.to_string(),
            if self.pass() { "pass" } else { "FAIL" }
        )
    }
}

/// The cases' workbench: one plugin registry for the whole run (each plugin
/// library loads once), a scratch folder for scenes and meshes, the size.
pub struct Bench<'p> {
    /// The run's size.
    pub size: Size,
    registry: Registry,
    dir: tempfile::TempDir,
    pool: &'p rayon::ThreadPool,
}

impl<'p> Bench<'p> {
    /// A workbench loading plugins from the standard path plus `extra`.
    pub fn new(size: Size, extra: &[PathBuf], pool: &'p rayon::ThreadPool) -> Result<Self> {
        Ok(Bench {
            size,
            registry: Registry::new(PluginPath::standard(extra)),
            dir: tempfile::Builder::new()
                .prefix("rtk-stress")
                .tempdir()
                .context("creating a scratch folder")?,
            pool,
        })
    }

    /// `quick` or `full`, by the run's size.
    pub fn n(&self, quick: usize, full: usize) -> usize {
        match self.size {
            Size::Quick => quick,
            Size::Full => full,
        }
    }

    /// The scratch folder scenes are read from (mesh files go here).
    pub fn dir(&self) -> &Path {
        self.dir.path()
    }

    /// Write a triangle mesh as OBJ, every coordinate printed so that it reads
    /// back as the same f32 (Rust's shortest round-trip form).
    pub fn write_obj(&self, name: &str, m: &Mesh) -> Result<PathBuf> {
        let mut s = String::with_capacity(m.verts.len() * 40 + m.tris.len() * 20);
        for v in &m.verts {
            let _ = writeln!(s, "v {:?} {:?} {:?}", v[0], v[1], v[2]);
        }
        for t in &m.tris {
            let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        let p = self.dir().join(name);
        std::fs::write(&p, s).with_context(|| format!("writing {}", p.display()))?;
        Ok(p)
    }

    /// Build a scene from TOML text (read as if from `case.toml` in the
    /// scratch folder), as `rtk render` would.
    pub fn scene(&mut self, toml: &str) -> Result<World> {
        let file = SceneFile::parse(&self.dir().join("case.toml"), toml.to_string())?;
        let desc = Desc::from_file(&file)?;
        Ok(rtk_shell::build(
            &file,
            desc,
            &mut self.registry,
            &Pool(self.pool),
        )?)
    }

    /// The error building a scene gives, or `None` when it builds.
    pub fn build_error(&mut self, toml: &str) -> Option<String> {
        match self.scene(toml) {
            Ok(_) => None,
            Err(e) => Some(format!("{e:#}")),
        }
    }

    /// Render a world through the render loop `rtk render` uses.
    pub fn render(&self, world: &World) -> Result<Film> {
        let r = &world.desc.render;
        let film = Film::new(r.width, r.height).map_err(anyhow::Error::msg)?;
        let tracer = Tracer::new(world);
        render_loop::render(&tracer, self.pool, false, film).map_err(anyhow::Error::msg)
    }
}

/// Traces single rays through a world's root on the calling thread.
pub struct Probe<'w> {
    world: &'w World,
    ctx: TraceCtx,
}

impl<'w> Probe<'w> {
    /// A probe on thread 0 of 1.
    pub fn new(world: &'w World) -> Self {
        Probe {
            world,
            ctx: TraceCtx::new(0, 1, 0),
        }
    }

    /// The nearest hit, if any.
    pub fn nearest(&mut self, ray: &Ray) -> Result<Option<Hit>> {
        let mut hit = Hit::new();
        let found = self.world.root.intersect(&mut self.ctx, ray, &mut hit);
        self.check()?;
        Ok(found.then_some(hit))
    }

    /// Whether anything lies on the ray's interval.
    pub fn occluded(&mut self, ray: &Ray) -> Result<bool> {
        let r = self.world.root.occluded(&mut self.ctx, ray);
        self.check()?;
        Ok(r)
    }

    /// The local geometry of a hit (everything).
    pub fn geom(&mut self, ray: &Ray, hit: &Hit) -> Result<LocalGeom> {
        let mut g = LocalGeom::EMPTY;
        self.world
            .root
            .local_geom(&mut self.ctx, ray, hit, geom_mask::ALL, &mut g);
        self.check()?;
        Ok(g)
    }

    fn check(&self) -> Result<()> {
        if let Some((class, msg)) = self.ctx.failure() {
            bail!("plugin `{class}` {msg}");
        }
        Ok(())
    }
}

/// A root ray from f64 origin and direction, rounded once to f32.
pub fn ray(o: DVec3, d: DVec3) -> Ray {
    Ray::new(o.as_vec3(), d.as_vec3())
}

/// A ray from f32 origin and direction.
pub fn ray32(o: Vec3, d: Vec3) -> Ray {
    Ray::new(o, d)
}

/// A uniformly distributed unit vector.
pub fn unit_vector(rng: &mut RngState) -> DVec3 {
    let z = 2.0 * rng.next_f64() - 1.0;
    let phi = std::f64::consts::TAU * rng.next_f64();
    let s = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(s * phi.cos(), s * phi.sin(), z)
}

/// A uniform direction in the hemisphere around `n`.
pub fn hemisphere(rng: &mut RngState, n: DVec3) -> DVec3 {
    let v = unit_vector(rng);
    if v.dot(n) < 0.0 {
        -v
    } else {
        v
    }
}

/// A uniformly random rotation (Arvo's method, Graphics Gems III).
pub fn rotation(rng: &mut RngState) -> DMat3 {
    let axis = unit_vector(rng);
    let angle = std::f64::consts::TAU * rng.next_f64();
    DMat3::from_axis_angle(axis, angle)
}

/// A TOML number that reads back as exactly `x` (`nan` and `inf` included).
pub fn num(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{x:?}")
    }
}

/// A magnitude for a setup label: `0`, `1e3`, `1e-3`.
pub fn mag(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else {
        format!("{x:e}")
    }
}

/// A TOML array of three numbers.
pub fn vec3(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", num(v[0]), num(v[1]), num(v[2]))
}

/// A TOML array of an f32 vector, exactly.
pub fn vec3f(v: Vec3) -> String {
    vec3([v.x as f64, v.y as f64, v.z as f64])
}

/// The `[render]` and camera tables a trace-only scene needs, rooted at
/// `root`.
pub fn header(root: &str) -> String {
    format!(
        "[render]\nroot = \"{root}\"\nintegrator = \"normals\"\nwidth = 8\nheight = 8\n\
         [cameras.none]\nclass = \"pinhole\"\n"
    )
}

/// A triangle mesh: f32 vertices and index triples.
pub struct Mesh {
    /// Vertices.
    pub verts: Vec<[f32; 3]>,
    /// Triangles.
    pub tris: Vec<[u32; 3]>,
}

/// A closed UV sphere about `c` with `rings` latitude bands and `segments`
/// longitudes, the radius of each vertex given by `radius(i)`. Poles and the
/// seam are shared vertices (pbrt-v4's `Triangle.Watertight` recipe), and the
/// vertices are rounded to f32 once, after adding the centre in f64.
pub fn uv_sphere(
    c: DVec3,
    rings: u32,
    segments: u32,
    mut radius: impl FnMut(usize) -> f64,
) -> Mesh {
    let mut verts = Vec::new();
    let mut push = |d: DVec3, verts: &mut Vec<[f32; 3]>| {
        let r = radius(verts.len());
        verts.push((c + d * r).as_vec3().to_array());
    };
    push(DVec3::Y, &mut verts);
    for i in 1..rings {
        let theta = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..segments {
            let phi = std::f64::consts::TAU * j as f64 / segments as f64;
            let d = DVec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            push(d, &mut verts);
        }
    }
    push(-DVec3::Y, &mut verts);
    let south = verts.len() as u32 - 1;
    let at = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
    let mut tris = Vec::new();
    for j in 0..segments {
        tris.push([0, at(1, j + 1), at(1, j)]);
        tris.push([south, at(rings - 1, j), at(rings - 1, j + 1)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segments {
            let (a, b, c2, d) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
            tris.push([a, b, d]);
            tris.push([a, d, c2]);
        }
    }
    Mesh { verts, tris }
}

/// The 12-triangle surface of the box `c ± h` (vertices rounded once).
pub fn box_mesh(c: DVec3, h: DVec3) -> Mesh {
    let verts = (0..8)
        .map(|i| {
            let s = DVec3::new(
                if i & 4 != 0 { 1.0 } else { -1.0 },
                if i & 2 != 0 { 1.0 } else { -1.0 },
                if i & 1 != 0 { 1.0 } else { -1.0 },
            );
            (c + s * h).as_vec3().to_array()
        })
        .collect();
    let tris = vec![
        [0, 1, 3],
        [0, 3, 2],
        [4, 6, 7],
        [4, 7, 5],
        [0, 4, 5],
        [0, 5, 1],
        [2, 3, 7],
        [2, 7, 6],
        [0, 2, 6],
        [0, 6, 4],
        [1, 5, 7],
        [1, 7, 3],
    ];
    Mesh { verts, tris }
}
