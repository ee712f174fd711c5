#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::glam::{DMat3, DMat4, Mat3, Vec3};
use rtk_kernel::sdk::texture::TextureParam;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;
use std::f32::consts::PI;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    radiance: TextureParam,
    #[serde(default = "one")]
    scale: f32,
    #[serde(default = "identity")]
    to_world: [f64; 16],
}

fn one() -> f32 {
    1.0
}
fn identity() -> [f64; 16] {
    DMat4::IDENTITY.to_cols_array()
}

/// Mitsuba's luminance weights (Rec. 709 Y).
fn luminance(c: [f32; 3]) -> f32 {
    0.212671 * c[0] + 0.715160 * c[1] + 0.072169 * c[2]
}

struct Envmap {
    /// Texels, row 0 at θ = 0 (the frame's +y), times `scale`.
    texels: Vec<[f32; 3]>,
    width: usize,
    height: usize,
    to_world: Mat3,
    to_local: Mat3,
    /// The sampling distribution over cells (see [`Cells`]).
    cells: Cells,
}

/// The sphere cut into `width` × (`height` − 1) cells, each spanning one
/// texel step in φ and θ between the texel centres that bilinear
/// interpolation blends. A cell is chosen in proportion to its mean
/// corner luminance (plus a floor, so that no direction the map lights
/// has zero density) times its solid angle, and a direction is uniform in
/// solid angle inside it: the density is then constant over each cell and
/// free of the 1/sin θ of a uv-uniform choice.
struct Cells {
    /// Per row: the cumulative weights of its cells, normalised to end at 1.
    conditional: Vec<f32>,
    /// Cumulative row weights, normalised to end at 1.
    marginal: Vec<f32>,
    /// Each cell's density (solid angle measure).
    density: Vec<f32>,
    /// cos θ at each row of texel centres.
    cos_theta: Vec<f32>,
}

impl Cells {
    fn new(lum: &[f32], w: usize, h: usize) -> Cells {
        let rows = h - 1;
        let cos_theta: Vec<f32> = (0..h)
            .map(|j| (PI * j as f32 / rows as f32).cos())
            .collect();
        let corner = |i: usize, j: usize| lum[j * w + i % w];
        let mean: Vec<f32> = (0..rows * w)
            .map(|k| {
                let (i, j) = (k % w, k / w);
                0.25 * (corner(i, j) + corner(i + 1, j) + corner(i, j + 1) + corner(i + 1, j + 1))
            })
            .collect();
        let avg = mean.iter().map(|&x| x as f64).sum::<f64>() / mean.len() as f64;
        let floor = (1e-3 * avg).max(1e-30) as f32;
        let mut conditional = vec![0.0f32; rows * w];
        let mut row_weight = vec![0.0f64; rows];
        for j in 0..rows {
            let band = (cos_theta[j] - cos_theta[j + 1]).max(0.0) as f64;
            let mut acc = 0.0f64;
            for i in 0..w {
                acc += (mean[j * w + i] + floor) as f64;
                conditional[j * w + i] = acc as f32;
            }
            for c in &mut conditional[j * w..(j + 1) * w] {
                *c /= acc as f32;
            }
            row_weight[j] = acc * band;
        }
        let total: f64 = row_weight.iter().sum();
        let mut acc = 0.0f64;
        let marginal = row_weight
            .iter()
            .map(|r| {
                acc += r;
                (acc / total) as f32
            })
            .collect();
        let dphi = 2.0 * std::f64::consts::PI / w as f64;
        let density = mean
            .iter()
            .map(|&m| ((m + floor) as f64 / (total * dphi)) as f32)
            .collect();
        Cells {
            conditional,
            marginal,
            density,
            cos_theta,
        }
    }
}

/// The index of the first entry of the cumulative `cdf` above `u`, and
/// `u` rescaled to [0, 1) within it.
fn pick(cdf: &[f32], u: f32) -> (usize, f32) {
    let i = cdf.partition_point(|&c| c <= u).min(cdf.len() - 1);
    let lo = if i == 0 { 0.0 } else { cdf[i - 1] };
    let span = cdf[i] - lo;
    let t = if span > 0.0 { (u - lo) / span } else { 0.5 };
    (i, t.clamp(0.0, 1.0 - f32::EPSILON))
}

/// A frame's rotation from a row-major 4 × 4 matrix: it must be one (an
/// environment map is at infinity: a translation means nothing, a scale
/// or shear would distort it).
fn rotation(m: &[f64; 16]) -> Result<Mat3, PluginError> {
    if !m.iter().all(|x| x.is_finite()) {
        return Err(PluginError::key("to_world", "must be finite numbers"));
    }
    let m4 = DMat4::from_cols_array(m).transpose();
    let r = DMat3::from_mat4(m4);
    let err = (r.transpose() * r - DMat3::IDENTITY).to_cols_array();
    if err.iter().any(|e| e.abs() > 1e-6) || r.determinant() < 0.0 {
        return Err(PluginError::key(
            "to_world",
            "must be a rotation (an environment map is at infinity: no scale, shear or mirror)",
        ));
    }
    Ok(r.as_mat3())
}

impl Plugin for Envmap {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        if !(p.scale >= 0.0 && p.scale.is_finite()) {
            return Err(PluginError::key("scale", "must be finite and ≥ 0"));
        }
        let to_world = rotation(&p.to_world)?;
        let tex = p.radiance.color("radiance", env)?;
        let Some((w, h, texels)) = tex.texels() else {
            return Err(PluginError::key(
                "radiance",
                "must be an image ({ image_file = \"...\" }): for one colour use the `constant` light",
            ));
        };
        let (width, height) = (w as usize, h as usize);
        if width < 2 || height < 3 {
            return Err(PluginError::key(
                "radiance",
                format!("a {w} x {h} image: an environment map needs at least 2 x 3 texels"),
            ));
        }
        let texels: Vec<[f32; 3]> = texels.iter().map(|t| t.map(|c| c * p.scale)).collect();
        let lum: Vec<f32> = texels.iter().map(|&t| luminance(t)).collect();
        let cells = Cells::new(&lum, width, height);
        Ok(Envmap {
            texels,
            width,
            height,
            to_world,
            to_local: to_world.transpose(),
            cells,
        })
    }
}

impl Envmap {
    /// Column and row coordinates of a local direction: x between texel
    /// centres in φ (periodic), y in θ with row 0 at the pole (Mitsuba's
    /// `direction_to_uv` and its texture's alignment).
    fn coords(&self, d: Vec3) -> (f32, f32) {
        let u = d.x.atan2(-d.z) / (2.0 * PI);
        let u = u - u.floor();
        let v = d.y.clamp(-1.0, 1.0).acos() / PI;
        (
            u * self.width as f32 - 0.5,
            v.clamp(0.0, 1.0) * (self.height - 1) as f32,
        )
    }

    /// The cell holding coordinates (x, y).
    fn cell(&self, x: f32, y: f32) -> (usize, usize) {
        let i = (x.floor() as i64).rem_euclid(self.width as i64) as usize;
        let j = (y.floor() as usize).min(self.height - 2);
        (i, j)
    }

    /// Radiance arriving from local direction `d`: bilinear between
    /// texel centres, periodic in φ, clamped in θ.
    fn radiance(&self, d: Vec3) -> Color {
        let (x, y) = self.coords(d);
        let (i, j) = self.cell(x, y);
        let (fx, fy) = (x - x.floor(), (y - j as f32).clamp(0.0, 1.0));
        let at = |i: usize, j: usize| self.texels[j * self.width + i % self.width];
        let mut c = [0.0f32; 3];
        for (di, dj, wt) in [
            (0, 0, (1.0 - fx) * (1.0 - fy)),
            (1, 0, fx * (1.0 - fy)),
            (0, 1, (1.0 - fx) * fy),
            (1, 1, fx * fy),
        ] {
            let t = at(i + di, j + dj);
            for k in 0..3 {
                c[k] += wt * t[k];
            }
        }
        Color::from_array(c)
    }
}

impl Light for Envmap {
    fn sample_li(
        &self,
        _ctx: &mut TraceCtx,
        _p: Vec3,
        u: [f32; 2],
        _time: f32,
    ) -> Option<LightSample> {
        let c = &self.cells;
        let (j, t) = pick(&c.marginal, u[1]);
        let w = self.width;
        let (i, s) = pick(&c.conditional[j * w..(j + 1) * w], u[0]);
        let cos = c.cos_theta[j] + t * (c.cos_theta[j + 1] - c.cos_theta[j]);
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let phi = 2.0 * PI * (i as f32 + 0.5 + s) / w as f32;
        let local = Vec3::new(phi.sin() * sin, cos, -phi.cos() * sin);
        let pdf = c.density[j * w + i];
        if !(pdf > 0.0) {
            return None;
        }
        Some(LightSample {
            wi: (self.to_world * local).normalize().into(),
            dist: f32::INFINITY,
            li: self.radiance(local),
            pdf,
        })
    }
}

impl Environment for Envmap {
    fn le(&self, _ctx: &mut TraceCtx, dir: Vec3) -> Color {
        self.radiance(self.to_local * dir.normalize())
    }

    fn pdf_li(&self, _ctx: &mut TraceCtx, _p: Vec3, wi: Vec3) -> f32 {
        let (x, y) = self.coords(self.to_local * wi.normalize());
        let (i, j) = self.cell(x, y);
        self.cells.density[j * self.width + i]
    }
}

rtk_kernel::export_light!(
    Envmap,
    class = "envmap",
    doc = include_str!("../README.md"),
    capabilities = [Environment]
);

#[cfg(test)]
mod tests {
    use super::*;

    /// The cells' densities integrate to 1 over the sphere, and each
    /// cell's density is its share of the weight over its solid angle.
    #[test]
    fn the_density_integrates_to_one() {
        let (w, h) = (7, 5);
        let lum: Vec<f32> = (0..w * h).map(|k| ((k * 37) % 11) as f32 + 0.1).collect();
        let c = Cells::new(&lum, w, h);
        let dphi = 2.0 * std::f64::consts::PI / w as f64;
        let mut total = 0.0f64;
        for j in 0..h - 1 {
            let band = (c.cos_theta[j] - c.cos_theta[j + 1]) as f64;
            for i in 0..w {
                total += c.density[j * w + i] as f64 * band * dphi;
            }
        }
        assert!((total - 1.0).abs() < 1e-5, "{total}");
        assert!((c.marginal[h - 2] - 1.0).abs() < 1e-6);
    }

    #[test]
    fn pick_inverts_a_cdf() {
        let cdf = [0.25, 0.25, 1.0];
        assert_eq!(pick(&cdf, 0.1).0, 0);
        assert_eq!(pick(&cdf, 0.25).0, 2);
        let (i, t) = pick(&cdf, 0.625);
        assert_eq!(i, 2);
        assert!((t - 0.5).abs() < 1e-6);
    }
}
