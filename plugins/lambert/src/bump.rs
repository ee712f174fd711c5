//! Bump and normal mapping: a height field over uv, or a map of normals in
//! the tangent frame, tilts the shading normal, as Mitsuba 3's `bumpmap`
//! and `normalmap` do around its `diffuse` (`src/bsdfs/bumpmap.cpp`,
//! `normalmap.cpp`, the shadowing of `normalmap_helpers.h`), so that `rtk
//! import` can translate those pairs exactly.
//!
//! A normal map's texel (r, g, b) is the normal 2·(r, g, b) − 1 in the
//! frame (s, t, n): n the shading normal, s = dp/du made perpendicular to
//! it (Gram–Schmidt), t = n × s — Mitsuba 3.9's shading frame.
//!
//! With h the height (the texture's luminance) times `bump_scale`, the
//! surface is displaced along the shading normal n: its tangents become
//! dp/du + n (∂h/∂u − n·dp/du) and likewise in v, and their cross product
//! is the tilted normal n′ (turned to the geometric normal's side, and
//! mirrored about n when the viewer would see it from behind). The
//! diffuse lobe is then evaluated about n′, and multiplied by Estevez et
//! al.'s shadowing term ("A Microfacet-Based Shadowing Function to Solve
//! the Bump Terminator Problem", Ray Tracing Gems 2019), which darkens
//! light arriving at grazing angles to the original surface.

use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::texture::Texture;
use rtk_kernel::*;

/// A height field and its scale.
pub struct Bump {
    height: Texture,
    scale: f32,
}

/// The tilted normal at one hit, for one viewer.
pub struct Tilted {
    /// n′, unit.
    pub n: Vec3,
    /// The untilted shading normal.
    ns: Vec3,
    /// The shadowing term's roughness², from n′'s tilt.
    alpha2: f32,
}

impl Bump {
    pub fn new(height: Texture, scale: f32) -> Result<Bump, PluginError> {
        if !scale.is_finite() {
            return Err(PluginError::key(
                "bump_scale",
                format!("must be a finite number, got {scale}"),
            ));
        }
        Ok(Bump { height, scale })
    }

    /// n′ at `g` seen from `wo`; `None` where the hit has no tangents (the
    /// integrator did not ask for them) or they are degenerate: the
    /// surface is then shaded unbumped.
    pub fn tilt(&self, g: &LocalGeom, wo: Vec3) -> Option<Tilted> {
        if g.filled & geom_mask::TANGENTS == 0 {
            return None;
        }
        let (ns, ng) = (g.ns.v(), g.ng.v());
        let (dpdu, dpdv) = (g.dpdu.v(), g.dpdv.v());
        let [hu, hv] = self.height.gradient(g.uv).map(|x| x * self.scale);
        let du = dpdu + ns * (hu - ns.dot(dpdu));
        let dv = dpdv + ns * (hv - ns.dot(dpdv));
        let mut n = du.cross(dv).normalize_or_zero();
        if n == Vec3::ZERO || !n.is_finite() {
            return None;
        }
        if ng.dot(n) < 0.0 {
            n = -n;
        }
        // Seen from behind: mirrored about ns (Mitsuba's flip_invalid_normals).
        let nz = n.dot(ns);
        if wo.dot(ns) * wo.dot(n) <= 0.0 {
            n = (2.0 * nz * ns - n).normalize_or(ns);
        }
        Some(Tilted {
            n,
            ns,
            alpha2: (0.125 * tan2(nz)).min(1.0),
        })
    }
}

/// A map of tangent-space normals (read raw: 2·texel − 1).
pub struct NormalMap {
    map: Texture,
}

impl NormalMap {
    pub fn new(map: Texture) -> NormalMap {
        NormalMap { map }
    }

    /// n′ at `g` seen from `wo`; `None` without tangents or where the
    /// frame or the texel is degenerate (the surface is then unmapped).
    pub fn tilt(&self, g: &LocalGeom, wo: Vec3) -> Option<Tilted> {
        if g.filled & geom_mask::TANGENTS == 0 {
            return None;
        }
        let (ns, dpdu) = (g.ns.v(), g.dpdu.v());
        let s = (dpdu - ns * ns.dot(dpdu)).normalize_or_zero();
        if s == Vec3::ZERO || !s.is_finite() {
            return None;
        }
        let t = ns.cross(s);
        let c = self.map.at(g).to_array();
        let mut n = Vec3::new(2.0 * c[0] - 1.0, 2.0 * c[1] - 1.0, 2.0 * c[2] - 1.0);
        // Seen from behind: mirrored about ns (flip_invalid_normals).
        let wl = Vec3::new(wo.dot(s), wo.dot(t), wo.dot(ns));
        if wl.z * wl.dot(n) <= 0.0 {
            n = Vec3::new(-n.x, -n.y, n.z);
        }
        let n = n.normalize_or_zero();
        if n == Vec3::ZERO || !n.is_finite() {
            return None;
        }
        Some(Tilted {
            n: (s * n.x + t * n.y + ns * n.z).normalize_or(ns),
            ns,
            alpha2: (0.125 * tan2(n.z)).min(1.0),
        })
    }
}

/// What tilts the shading normal.
pub enum Tilt {
    /// A height field.
    Bump(Bump),
    /// A map of normals.
    Normals(NormalMap),
}

impl Tilt {
    pub fn tilt(&self, g: &LocalGeom, wo: Vec3) -> Option<Tilted> {
        match self {
            Tilt::Bump(b) => b.tilt(g, wo),
            Tilt::Normals(m) => m.tilt(g, wo),
        }
    }
}

/// tan²θ for cos θ = `c` (infinite at c = 0).
#[inline]
fn tan2(c: f32) -> f32 {
    (1.0 - c * c).max(0.0) / (c * c)
}

impl Tilted {
    /// The shadowing of light (or view) along `w`: 2 / (1 + √(1 + α² tan²θ)),
    /// θ from the untilted normal.
    pub fn shadowing(&self, w: Vec3) -> f32 {
        let g = 2.0 / (1.0 + (1.0 + self.alpha2 * tan2(w.dot(self.ns))).sqrt());
        if g.is_finite() {
            g
        } else {
            0.0
        }
    }

    /// Does `w` leave on the same side of both normals? (Else the tilted
    /// lobe would send light through the surface.)
    pub fn agrees(&self, w: Vec3) -> bool {
        w.dot(self.ns) * w.dot(self.n) > 0.0
    }

    /// `wo` and `wi` both above n′ and each on one side of both normals:
    /// where the bumped lobe is not zero.
    pub fn admits(&self, wo: Vec3, wi: Vec3) -> bool {
        wo.dot(self.n) > 0.0 && wi.dot(self.n) > 0.0 && self.agrees(wi)
    }
}
