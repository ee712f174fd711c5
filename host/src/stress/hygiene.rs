//! V1–V3: IEEE hygiene. Ray intervals at their edges through the real
//! plugins, invalid scene parameters refused with the object and key named,
//! and no non-finite value anywhere in the example scenes' renders.

use super::bench::*;
use super::Case;
use anyhow::{bail, Context, Result};
use rtk_kernel::abi::{Hit, Ray};
use rtk_kernel::geom::{intersect_sphere, nearest_root, spawn_ray_to};
use rtk_kernel::glam::{DAffine3, DVec3};
use rtk_kernel::RngState;
use rtk_shell::{Desc, PluginPath, Registry, SceneFile, World};
use std::path::{Path, PathBuf};

/// docs/numerics.md V1.
pub const V1: Case = Case {
    id: "V1",
    title: "ray intervals at their edges: open, finite, NaN-false",
    run: ray_intervals_are_open_at_their_edges,
};

/// docs/numerics.md V2.
pub const V2: Case = Case {
    id: "V2",
    title: "invalid scene parameters refused, naming object and key",
    run: invalid_parameters_are_refused_naming_object_and_key,
};

/// docs/numerics.md V3.
pub const V3: Case = Case {
    id: "V3",
    title: "no non-finite value in any example scene's render",
    run: example_scenes_render_no_non_finite_value,
};

/// Reported hits that break rule 2: non-finite t, or t outside the open
/// interval (t_min, t_max).
#[derive(Default)]
struct Interval {
    non_finite: u64,
    outside: u64,
}

impl Interval {
    fn check(&mut self, ray: &Ray, hit: Option<Hit>) -> Option<Hit> {
        let h = hit?;
        if !h.t.is_finite() {
            self.non_finite += 1;
        } else if !(h.t > ray.t_min && h.t < ray.t_max) {
            self.outside += 1;
        }
        Some(h)
    }
}

/// The sphere of the V1 scenes: radius 5 so that the 3-4-5 points c + (3,
/// 4, 0) and their permutations lie exactly on it in f32.
const BALL_C: [f64; 3] = [10.0, 20.0, 30.0];
const BALL_R: f64 = 5.0;

/// The catalogue's V1 through three objects: a triangle (the `mesh`
/// plugin under its BVH), a sphere, and the sphere under an instance
/// transform. For each: origins exactly on the surface with t_min = 0
/// (the interval is open: the origin itself is not a hit), t_max = ∞ against
/// f32::MAX (the same answers), every hit re-traced with t_max and then t_min
/// set exactly to its t (never reported again), and shadow rays with an
/// unnormalised direction and t_max = 1 − 1e-4 (`spawn_ray_to`) from the
/// triangle to points on the sphere, which must not report their target.
fn ray_intervals_are_open_at_their_edges(b: &mut Bench) -> Result<Vec<Line>> {
    let n = b.n(20_000, 200_000);
    b.write_obj(
        "triangle.obj",
        &Mesh {
            verts: vec![[-4.0, -4.0, 0.0], [4.0, -4.0, 0.0], [0.0, 4.0, 0.0]],
            tris: vec![[0, 1, 2]],
        },
    )?;
    let ball = format!(
        "[objects.ball]\nclass = \"sphere\"\ncenter = {}\nradius = {}\n",
        vec3(BALL_C),
        num(BALL_R)
    );
    let mut lines = Vec::new();
    let mut rng = RngState::seeded(0x91);
    for (name, root) in [
        ("triangle", "{ object = \"tri\" }".to_string()),
        ("sphere", "{ object = \"ball\" }".to_string()),
        (
            "moved sphere",
            "{ object = \"ball\", transform = [{ rotate = { axis = [1.0, 2.0, 3.0], angle = 40.0 } }, \
             { translate = [-7.5, 3.25, 100.0] }] }"
                .to_string(),
        ),
    ] {
        let world = b.scene(&format!(
            "{}[objects.tri]\nclass = \"mesh\"\nfile = \"triangle.obj\"\n{ball}\
             [objects.world]\nclass = \"list\"\nchildren = [{root}]\n",
            header("world")
        ))?;
        let (centre, size) = where_v1_object_is(name);
        let mut o = Traced {
            name,
            probe: Probe::new(&world),
            iv: Interval::default(),
            centre,
            size,
        };
        // Origins exactly on the surface (untransformed objects only: under
        // a transform no f32 point lies exactly on the surface).
        if name != "moved sphere" {
            lines.push(Line::count(
                format!("{name}: origin on it, t_min 0"),
                "self-hits or lost far side",
                o.origins_on_the_surface(&mut rng, n)?,
            ));
        }
        let (differ, repeated) = o.rays_at_the_interval_edges(&mut rng, n)?;
        lines.push(Line::count(
            format!("{name}: t_max inf vs f32::MAX"),
            "different answers",
            differ,
        ));
        lines.push(Line::count(
            format!("{name}: t_max, t_min = hit t"),
            "hit reported again",
            repeated,
        ));
        if name != "triangle" {
            lines.push(Line::count(
                format!("{name}: shadow rays, t_max 1-1e-4"),
                "target reported",
                o.shadow_rays_from_the_triangle(b, &mut rng, n)?,
            ));
        }
        let iv = &o.iv;
        lines.push(Line::count(format!("{name}: all rays"), "non-finite t", iv.non_finite));
        lines.push(Line::count(
            format!("{name}: all rays"),
            "t outside (t_min, t_max)",
            iv.outside,
        ));
    }
    Ok(lines)
}

/// Where V1's object `name` is in the world, for aiming rays at it: its
/// centre and size.
fn where_v1_object_is(name: &str) -> (DVec3, f64) {
    match name {
        "triangle" => (DVec3::ZERO, 4.0),
        "sphere" => (DVec3::from(BALL_C), BALL_R),
        _ => {
            let m = DAffine3::from_translation(DVec3::new(-7.5, 3.25, 100.0))
                * DAffine3::from_axis_angle(
                    DVec3::new(1.0, 2.0, 3.0).normalize(),
                    40f64.to_radians(),
                );
            (m.transform_point3(DVec3::from(BALL_C)), BALL_R)
        }
    }
}

/// One of V1's objects, traced alone, with the interval breaches of every
/// hit it reports.
struct Traced<'w> {
    name: &'static str,
    probe: Probe<'w>,
    iv: Interval,
    centre: DVec3,
    size: f64,
}

impl Traced<'_> {
    /// Rays from points exactly on the surface, t_min = 0: those leaving a
    /// plane or a convex surface must hit nothing, those into the sphere
    /// its far side at the f64 chord. Returns the failures.
    fn origins_on_the_surface(&mut self, rng: &mut RngState, n: usize) -> Result<u64> {
        let mut self_hits = 0u64;
        for _ in 0..n {
            let (o, normal) = if self.name == "triangle" {
                // Points of a 1/8 grid inside the triangle, in its plane.
                let (x, y) = loop {
                    let x = (rng.next_f64() * 64.0 - 32.0).round() / 8.0;
                    let y = (rng.next_f64() * 64.0 - 32.0).round() / 8.0;
                    if y > -4.0 && y < 4.0 - 2.0 * x.abs() {
                        break (x, y);
                    }
                };
                (DVec3::new(x, y, 0.0), DVec3::Z)
            } else {
                let k = on_sphere(rng);
                (DVec3::from(BALL_C) + k, k / BALL_R)
            };
            let d = unit_vector(rng);
            let r = ray(o, d);
            let got = self.iv.check(&r, self.probe.nearest(&r)?);
            let outward = d.dot(normal) > 0.0;
            if self.name == "triangle" || outward {
                // Leaving a plane or a convex surface: nothing to hit.
                self_hits += u64::from(got.is_some());
            } else {
                self_hits += u64::from(far_side_lost(&r, got));
            }
        }
        Ok(self_hits)
    }

    /// Rays from outside at the object: t_max = ∞ and f32::MAX must agree,
    /// and a hit is never reported again with t_max or t_min set to its t.
    /// Returns (differing answers, hits reported again).
    fn rays_at_the_interval_edges(&mut self, rng: &mut RngState, n: usize) -> Result<(u64, u64)> {
        let (mut differ, mut repeated) = (0u64, 0u64);
        for _ in 0..n {
            let o = self.centre + unit_vector(rng) * (self.size * 4.0);
            let aim = self.centre + unit_vector(rng) * (self.size * rng.next_f64());
            let r = ray(o, aim - o);
            let inf = self.iv.check(&r, self.probe.nearest(&r)?);
            let max = Ray {
                t_max: f32::MAX,
                ..r
            };
            let fin = self.iv.check(&max, self.probe.nearest(&max)?);
            if inf.map(|h| h.t.to_bits()) != fin.map(|h| h.t.to_bits()) {
                differ += 1;
            }
            let Some(h) = inf else { continue };
            let below = Ray { t_max: h.t, ..r };
            let above = Ray { t_min: h.t, ..r };
            for q in [below, above] {
                if self
                    .iv
                    .check(&q, self.probe.nearest(&q)?)
                    .is_some_and(|x| x.t == h.t)
                {
                    repeated += 1;
                }
            }
        }
        Ok((differ, repeated))
    }

    /// Shadow rays from the triangle's plane (z = 0 below the sphere) to
    /// points on the sphere's near side (`spawn_ray_to`): the target must
    /// not be reported. Returns how often it was.
    fn shadow_rays_from_the_triangle(
        &mut self,
        b: &mut Bench,
        rng: &mut RngState,
        n: usize,
    ) -> Result<u64> {
        let mut reported = 0u64;
        let floor = b.scene(&format!(
            "{}[objects.tri]\nclass = \"mesh\"\nfile = \"triangle.obj\"\n\
             [objects.world]\nclass = \"list\"\nchildren = [\"tri\"]\n",
            header("world")
        ))?;
        let mut floor_probe = Probe::new(&floor);
        for _ in 0..n {
            // A point of the triangle, seen from below.
            let p = DVec3::new(rng.next_f64() * 2.0 - 1.0, rng.next_f64() * 2.0 - 1.0, 0.0);
            let up = ray(p - DVec3::Z, DVec3::Z);
            let Some(fh) = floor_probe.nearest(&up)? else {
                continue;
            };
            let fg = floor_probe.geom(&up, &fh)?;
            // The first point of the sphere towards a random aim.
            let aim = self.centre + unit_vector(rng) * (self.size * rng.next_f64());
            let look = ray(p, aim - p);
            let Some(bh) = self.probe.nearest(&look)? else {
                continue;
            };
            let target = self.probe.geom(&look, &bh)?.p.v();
            let s = spawn_ray_to(&fg, target, &up);
            let got = self.iv.check(&s, self.probe.nearest(&s)?);
            if got.is_some() || self.probe.occluded(&s)? {
                reported += 1;
            }
        }
        Ok(reported)
    }
}

/// Whether `got`, for a ray from the sphere's surface into it, misses the
/// far side at the f64 chord.
fn far_side_lost(r: &Ray, got: Option<Hit>) -> bool {
    let chord = intersect_sphere(
        BALL_C,
        BALL_R,
        r.origin.v().as_dvec3().to_array(),
        r.dir.v().as_dvec3().to_array(),
    )
    .and_then(|h| nearest_root(&h, 0.0, f64::INFINITY));
    // A hit at t ≈ 0 is the origin itself. A near-tangent
    // ray dips nanometres deep: chords below 1e-2 r (depth
    // 1.25e-5 r) lie in the discriminant's error band (a few
    // ε r deep), so only longer ones must not be lost.
    match (got, chord) {
        (Some(h), Some(t)) => h.t as f64 <= 1e-3 * t,
        (Some(h), None) => h.t as f64 <= 1e-6 * BALL_R,
        (None, Some(t)) => t >= 1e-2 * BALL_R,
        (None, None) => false,
    }
}

/// A random point of the radius-5 sphere about the origin that is exact in
/// f32: a signed permutation of (3, 4, 0) or (5, 0, 0).
fn on_sphere(rng: &mut RngState) -> DVec3 {
    let base = if rng.next_f64() < 0.8 {
        [3.0, 4.0, 0.0]
    } else {
        [5.0, 0.0, 0.0]
    };
    let perm = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ][(rng.next_u32() % 6) as usize];
    let mut v = [0.0; 3];
    for i in 0..3 {
        let s = if rng.next_u32() & 1 == 0 { 1.0 } else { -1.0 };
        v[i] = s * base[perm[i]];
    }
    DVec3::from(v)
}

/// The parts of a V2 scene; each fault replaces one.
#[derive(Clone)]
struct Parts {
    integrator: String,
    background: String,
    camera: String,
    light: String,
    shader: String,
    ball: String,
    mesh: bool,
    transform: String,
}

impl Default for Parts {
    fn default() -> Self {
        Parts {
            integrator: "\"whitted\"".into(),
            background: "[0.0, 0.0, 0.0]".into(),
            camera: "class = \"pinhole\"\neye = [0.0, 0.0, 5.0]\nfov_y = 40.0\n".into(),
            light: "class = \"point\"\nposition = [0.0, 5.0, 5.0]\nintensity = [1.0, 1.0, 1.0]\n"
                .into(),
            shader: "class = \"lambert\"\nalbedo = [0.5, 0.5, 0.5]\n".into(),
            ball: "class = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n".into(),
            mesh: false,
            transform: String::new(),
        }
    }
}

impl Parts {
    fn toml(&self) -> String {
        let transform = if self.transform.is_empty() {
            String::new()
        } else {
            format!(", transform = {}", self.transform)
        };
        let mesh = if self.mesh {
            ", { object = \"m\" }"
        } else {
            ""
        };
        format!(
            "[render]\nroot = \"world\"\nwidth = 8\nheight = 8\nintegrator = {}\nbackground = {}\n\
             [cameras.c]\n{}[lights.l]\n{}[shaders.s]\n{}[objects.ball]\n{}\
             [objects.m]\nclass = \"mesh\"\nfile = \"fault.obj\"\n\
             [objects.world]\nclass = \"list\"\nchildren = [{{ object = \"ball\", shader = \"s\"{transform} }}{mesh}]\n",
            self.integrator,
            self.background,
            self.camera,
            self.light,
            self.shader,
            self.ball
        )
    }
}

/// One invalid input: what it is, the scene's change, and the object and
/// key its error must name.
struct Fault {
    what: String,
    parts: Parts,
    obj: Option<String>,
    object: &'static str,
    key: &'static str,
}

/// The catalogue's V2 faults, one scene each. Motion time ranges and
/// emission are absent: rtk has no motion blur and no emitters but lights.
fn faults() -> Vec<Fault> {
    let base = Parts::default();
    let mut v = Vec::new();
    sphere_and_transform_faults(&mut v, &base);
    camera_and_light_faults(&mut v, &base);
    shader_and_render_faults(&mut v, &base);
    mesh_faults(&mut v, &base);
    v
}

/// Add the fault `what`: the base scene changed by `f`, whose error must
/// name `object` and `key`.
fn add(
    v: &mut Vec<Fault>,
    base: &Parts,
    what: &str,
    object: &'static str,
    key: &'static str,
    f: &dyn Fn(&mut Parts),
) {
    let mut parts = base.clone();
    f(&mut parts);
    v.push(Fault {
        what: what.into(),
        parts,
        obj: None,
        object,
        key,
    });
}

/// A sphere's radius and centre, an instance's transform.
fn sphere_and_transform_faults(v: &mut Vec<Fault>, base: &Parts) {
    for (what, r) in [
        ("radius nan", "nan"),
        ("radius inf", "inf"),
        ("radius 0", "0.0"),
        ("radius -1", "-1.0"),
        ("radius 1e-40", "1e-40"),
    ] {
        add(v, base, what, "objects.ball", "radius", &|p| {
            p.ball = format!("class = \"sphere\"\nradius = {r}\n");
        });
    }
    for (what, c) in [
        ("center nan", "[nan, 0.0, 0.0]"),
        ("center 1e13", "[0.0, 1e13, 0.0]"),
    ] {
        add(v, base, what, "objects.ball", "center", &|p| {
            p.ball = format!("class = \"sphere\"\ncenter = {c}\n");
        });
    }
    let shear = |k: f64| {
        let s = (k - 3.0).sqrt();
        format!(
            "[{{ matrix = [1.0, {}, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0] }}]",
            num(s)
        )
    };
    for (what, t) in [
        (
            "transform nan",
            "[{ translate = [nan, 0.0, 0.0] }]".to_string(),
        ),
        (
            "transform matrix nan",
            "[{ matrix = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, nan, 0.0] }]".into(),
        ),
        ("transform det 0", "[{ scale = [1.0, 0.0, 1.0] }]".into()),
        ("transform condition 1e9", shear(1e9)),
        ("transform scale 1e-20", "[{ scale = 1e-20 }]".into()),
        (
            "transform translate 1e13",
            "[{ translate = [1e13, 0.0, 0.0] }]".into(),
        ),
    ] {
        add(
            v,
            base,
            what,
            "objects.world.children[0]",
            "transform",
            &|p| {
                p.transform = t.clone();
            },
        );
    }
}

/// A camera's view, a light's power and placement.
fn camera_and_light_faults(v: &mut Vec<Fault>, base: &Parts) {
    for (what, key, cam) in [
        ("fov 0", "fov_y", "fov_y = 0.0\n"),
        ("fov 180", "fov_y", "fov_y = 180.0\n"),
        ("fov -10", "fov_y", "fov_y = -10.0\n"),
        ("fov nan", "fov_y", "fov_y = nan\n"),
        ("eye inf", "eye", "eye = [inf, 0.0, 0.0]\n"),
        (
            "look_at = eye",
            "look_at",
            "eye = [1.0, 2.0, 3.0]\nlook_at = [1.0, 2.0, 3.0]\n",
        ),
        ("up along view", "up", "up = [0.0, 0.0, 1.0]\n"),
    ] {
        add(v, base, what, "cameras.c", key, &|p| {
            p.camera = format!("class = \"pinhole\"\n{cam}");
        });
    }
    for (what, key, light) in [
        (
            "intensity -1",
            "intensity",
            "class = \"point\"\nintensity = [-1.0, 1.0, 1.0]\n",
        ),
        (
            "intensity nan",
            "intensity",
            "class = \"point\"\nintensity = [1.0, nan, 1.0]\n",
        ),
        (
            "light position 1e13",
            "position",
            "class = \"point\"\nposition = [0.0, 0.0, 1e13]\n",
        ),
        (
            "direction 0",
            "direction",
            "class = \"directional\"\ndirection = [0.0, 0.0, 0.0]\n",
        ),
        (
            "irradiance -1",
            "irradiance",
            "class = \"directional\"\nirradiance = [1.0, -1.0, 1.0]\n",
        ),
    ] {
        add(v, base, what, "lights.l", key, &|p| p.light = light.into());
    }
}

/// A shader's parameters, the integrator's depth, the background.
fn shader_and_render_faults(v: &mut Vec<Fault>, base: &Parts) {
    for (what, key, shader) in [
        (
            "albedo 1.5",
            "albedo",
            "class = \"lambert\"\nalbedo = [1.5, 0.5, 0.5]\n",
        ),
        (
            "albedo -0.1",
            "albedo",
            "class = \"lambert\"\nalbedo = [-0.1, 0.5, 0.5]\n",
        ),
        ("ior 0", "ior", "class = \"phong\"\nior = 0.0\n"),
        ("ior nan", "ior", "class = \"phong\"\nior = nan\n"),
        (
            "shininess -1",
            "shininess",
            "class = \"phong\"\nshininess = -1.0\n",
        ),
    ] {
        add(v, base, what, "shaders.s", key, &|p| {
            p.shader = shader.into()
        });
    }
    add(
        v,
        base,
        "max_depth -1",
        "render.integrator",
        "max_depth",
        &|p| {
            p.integrator = "{ class = \"whitted\", max_depth = -1 }".into();
        },
    );
    add(v, base, "background nan", "render", "background", &|p| {
        p.background = "[0.0, nan, 0.0]".into();
    });
}

/// A mesh file's vertices and indices.
fn mesh_faults(v: &mut Vec<Fault>, base: &Parts) {
    for (what, obj) in [
        ("vertex nan", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
        ("vertex inf", "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n"),
        ("vertex -inf", "v 0 0 0\nv 1 0 0\nv 0 -inf 0\nf 1 2 3\n"),
        ("vertex 1e13", "v 0 0 0\nv 1 0 0\nv 0 0 1e13\nf 1 2 3\n"),
        ("vertex 1e39", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n"),
        ("index out of range", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"),
        ("index 0", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"),
        ("index -4", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n"),
    ] {
        let mut parts = base.clone();
        parts.mesh = true;
        v.push(Fault {
            what: what.into(),
            parts,
            obj: Some(obj.into()),
            object: "objects.m",
            key: "file",
        });
    }
}

/// The catalogue's V2: every invalid input refused when the scene is built
/// (the base scene builds), and each error naming the object and the key,
/// so that the user can find what to fix.
fn invalid_parameters_are_refused_naming_object_and_key(b: &mut Bench) -> Result<Vec<Line>> {
    let base = Parts {
        mesh: true,
        ..Parts::default()
    };
    std::fs::write(
        b.dir().join("fault.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )?;
    if let Some(e) = b.build_error(&base.toml()) {
        bail!("the valid V2 scene does not build: {e}");
    }
    let faults = faults();
    let (mut accepted, mut unnamed) = (Vec::new(), Vec::new());
    for f in &faults {
        let obj = f
            .obj
            .as_deref()
            .unwrap_or("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        std::fs::write(b.dir().join("fault.obj"), obj)?;
        match b.build_error(&f.parts.toml()) {
            None => accepted.push(f.what.clone()),
            Some(e) => {
                let names_key = e.contains(&format!("key `{}", f.key));
                if !(e.contains(f.object) && names_key) {
                    unnamed.push(f.what.clone());
                }
            }
        }
    }
    let label = |what: &str, list: &[String]| {
        if list.is_empty() {
            format!("{} faults", faults.len())
        } else {
            format!("{what}: {}", list.join(", "))
        }
    };
    Ok(vec![
        Line::count(
            label("accepted", &accepted),
            "invalid inputs accepted",
            accepted.len() as u64,
        ),
        Line::count(
            label("unnamed", &unnamed),
            "errors missing object or key",
            unnamed.len() as u64,
        ),
    ])
}

/// The example scenes: `scenes/` beside the workspace this binary was
/// built from, else `scenes/` in the working directory.
fn scenes_dir() -> Result<PathBuf> {
    let built = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    for d in [built, PathBuf::from("scenes")] {
        if d.is_dir() {
            return Ok(d);
        }
    }
    bail!("no scenes folder (looked beside the source tree and in the working directory)")
}

/// Build a scene file from its own path, as `rtk render --set` would, so
/// that the files it names resolve against its folder. With a registry and
/// a pool of its own (the bench's are private to bench.rs; a library loaded
/// twice is mapped once): it searches the standard plugin path, without
/// `--plugin-path`.
fn build_file(
    path: &Path,
    sets: &[String],
    registry: &mut Registry,
    pool: &rayon::ThreadPool,
) -> Result<World> {
    let mut file = SceneFile::read(path)?;
    file.apply_overrides(sets)?;
    let desc = Desc::from_file(&file)?;
    Ok(rtk_shell::build(
        &file,
        desc,
        registry,
        &crate::shared::threads::Pool(pool),
    )?)
}

/// The catalogue's V3: every scene in scenes/ rendered small through the
/// render loop; the film drops a non-finite sample and counts it, so both
/// the dropped samples and any non-finite pixel value are counted.
fn example_scenes_render_no_non_finite_value(b: &mut Bench) -> Result<Vec<Line>> {
    let (w, h) = (b.n(64, 320), b.n(48, 240));
    let dir = scenes_dir()?;
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(&dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    scenes.sort();
    if scenes.is_empty() {
        bail!("no scenes in {}", dir.display());
    }
    let mut registry = Registry::new(PluginPath::standard(&[]));
    let pool = rayon::ThreadPoolBuilder::new()
        .build()
        .context("starting a thread pool")?;
    let sets = [
        format!("render.width={w}"),
        format!("render.height={h}"),
        "render.spp=1".to_string(),
    ];
    let mut lines = Vec::new();
    for s in &scenes {
        let world = build_file(s, &sets, &mut registry, &pool)
            .with_context(|| format!("building {}", s.display()))?;
        let film = b.render(&world)?;
        let bad = film
            .pixels
            .iter()
            .flatten()
            .filter(|v| !v.is_finite())
            .count() as u64;
        let name = s
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        lines.push(Line::count(
            format!("{name}, {w}x{h}"),
            "non-finite samples + pixels",
            film.stats.nonfinite_samples + bad,
        ));
    }
    Ok(lines)
}
