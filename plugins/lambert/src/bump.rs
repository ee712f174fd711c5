//! Bump mapping: a height field over uv tilts the shading normal, as
//! Mitsuba 3's `bumpmap` does around its `diffuse` (`src/bsdfs/bumpmap.cpp`,
//! the shadowing of `normalmap_helpers.h`), so that `rtk import` can
//! translate that pair exactly.
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
