//! `rtk conform` for shader plugins: the material queries' contracts,
//! checked by Monte Carlo on a surface facing +z, for a few outgoing
//! directions (near the normal, at 45°, grazing) on both sides.
//!
//! - `finite`: no query returns NaN or infinity;
//! - `energy`: the mean sample weight (f·|cos|/pdf) is at most 1, within
//!   5 standard errors: a material reflects no more than it receives;
//! - `weight-matches-eval`: for samples of non-delta lobes, the weight is
//!   eval·|cos|/pdf (the integrator's estimate is consistent);
//! - `pdf-matches-sample`: `pdf(wi)` is the density `sample` reported;
//! - `pdf-integrates`: ∫ pdf dω over the sphere (uniform-sphere Monte Carlo)
//!   equals the share of non-delta samples, within 5 standard errors: a
//!   density that does not integrate biases MIS;
//! - `reciprocity`: f(wo, wi) = f(wi, wo) for reflection, where the shader
//!   has no transmission lobe.
//!
//! A shader that reports no density (`pdf` → `None`) skips the pdf checks,
//! saying so: it is allowed, and the path tracer then does not weigh its
//! samples by MIS.

use crate::conform::{brief, note, readme_examples, unknown_key, Check, Cx, Suite};
use anyhow::{anyhow, Result};
use rtk_handles::{CreateArgs, Shader};
use rtk_kernel::abi::{geom_mask, lobe, Float3, LocalGeom, ShaderModuleRef};
use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::shading::uniform_sphere;
use rtk_kernel::{RngState, TraceCtx};

/// The checks for shader class `cx.class` from `module`.
pub fn checks(module: ShaderModuleRef, cx: &mut Cx, suite: &mut Suite) -> Result<()> {
    suite.at("create");
    let shader = create(module, cx, suite)?;
    let n = cx.n(4000, 40000);
    suite.at("finite");
    let mut ctx = TraceCtx::new(0, 1, 0);
    let mut g = LocalGeom::EMPTY;
    g.p = Vec3::ZERO.into();
    g.ng = Vec3::Z.into();
    g.ns = Vec3::Z.into();
    g.dpdu = Vec3::X.into();
    g.dpdv = Vec3::Y.into();
    g.uv = [0.5, 0.5];
    g.filled = geom_mask::ALL;
    let mut probe = Probe {
        shader: &shader,
        ctx: &mut ctx,
        g: &g,
        transmits: shader.lobes() & lobe::TRANSMISSION != 0,
        rng: RngState::seeded(0x5ade),
        n,
    };
    let mut t = Tallies {
        nonfinite: (0, String::new()),
        energy: (true, String::new()),
        weight_bad: (0, String::new()),
        pdf_bad: (0, String::new()),
        integral_bad: (true, String::new()),
        recip_bad: (0, String::new()),
        pdf_known: true,
    };
    for side in [1.0f32, -1.0] {
        for theta in [0.15f32, 0.785, 1.45] {
            let wo = Vec3::new(theta.sin(), 0.0, side * theta.cos());
            probe.direction(wo, &mut t);
        }
    }
    let transmits = probe.transmits;
    if let Some((c, m)) = ctx.failure() {
        return Err(anyhow!("plugin `{c}` {m}"));
    }
    push_checks(suite, &t, transmits);
    suite.at("unknown-key-refused");
    let c = unknown_key(cx, 0);
    suite.push(c);
    super::panics::run(cx, suite, 0)?;
    Ok(())
}

/// Create the shader with `--params`; when it refuses none and no
/// `--params` was given, with the first of its README's examples it takes.
fn create(module: ShaderModuleRef, cx: &mut Cx, suite: &mut Suite) -> Result<Shader> {
    let args = CreateArgs {
        scene_dir: ".",
        name: "shaders.conform",
        image_width: 1,
        image_height: 1,
        origin: [0.0; 3],
        arrays: &[],
    };
    let class = cx.class.clone();
    Ok(match Shader::create(module, &cx.params.json(), &args) {
        Ok(s) => s,
        Err(e) if cx.args.params.is_none() => {
            // Parameters it cannot do without: its README's examples.
            let mut found = None;
            for mut ex in readme_examples(&cx.doc, &class) {
                if ex.resolve_files(std::path::Path::new("")).is_err() {
                    continue;
                }
                if let Ok(s) = Shader::create(module, &ex.json(), &args) {
                    suite.push(Check::pass(
                        "params",
                        format!(
                            "none refused ({}); using the README's example: {}",
                            brief(&e.to_string()),
                            ex.shown()
                        ),
                    ));
                    cx.params = ex;
                    found = Some(s);
                    break;
                }
            }
            found.ok_or_else(|| anyhow!("`{class}` refused to be created without parameters: {e} (nor do the README's examples work; give --params)"))?
        }
        Err(e) => return Err(anyhow!("`{class}` refused --params: {e}")),
    })
}

/// What the Monte Carlo checks found: failures (count, first), and for
/// `energy` and `pdf-integrates` whether they held (and the first miss).
struct Tallies {
    nonfinite: (u64, String),
    energy: (bool, String),
    weight_bad: (u64, String),
    pdf_bad: (u64, String),
    integral_bad: (bool, String),
    recip_bad: (u64, String),
    /// Whether the shader reports densities (`pdf` gave one every time).
    pdf_known: bool,
}

/// The shader on the surface facing +z, queried as an integrator would.
struct Probe<'a> {
    shader: &'a Shader,
    ctx: &'a mut TraceCtx,
    g: &'a LocalGeom,
    transmits: bool,
    rng: RngState,
    /// Samples per outgoing direction.
    n: usize,
}

impl Probe<'_> {
    /// All the checks for outgoing direction `wo`, into `t`.
    fn direction(&mut self, wo: Vec3, t: &mut Tallies) {
        let n = self.n;
        let (mut sum, mut sum2, mut nonzero_share) = (0.0f64, 0.0f64, 0.0f64);
        for k in 0..n {
            // Stratified in the first number: the estimate converges faster.
            let u = [
                (k as f32 + self.rng.next_f32()) / n as f32,
                self.rng.next_f32(),
            ];
            let Some(s) = self.shader.sample(self.ctx, self.g, f3(wo), u, lobe::ALL) else {
                continue;
            };
            let w = s.weight;
            if !(w.is_finite() && s.pdf.is_finite() && s.wi.v().is_finite()) {
                note(&mut t.nonfinite, || {
                    format!("sample at wo {wo:?} gave {s:?}")
                });
                continue;
            }
            let m = w.r.max(w.g).max(w.b) as f64;
            sum += m;
            sum2 += m * m;
            if s.lobe & lobe::SPECULAR != 0 {
                continue;
            }
            nonzero_share += 1.0 / n as f64;
            self.non_delta_sample(wo, &s, t);
        }
        let mean = sum / n as f64;
        let se = ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
        if mean > 1.0 + 5.0 * se + 1e-3 && t.energy.0 {
            t.energy = (
                false,
                format!("at wo {wo:?} the mean weight is {mean:.4} ± {se:.4}: it creates energy"),
            );
        }
        if t.pdf_known {
            self.pdf_integral(wo, nonzero_share, t);
        }
    }

    /// A sample of a non-delta lobe: its weight is eval·|cos|/pdf, `pdf`
    /// gives its density, and (for reflection) eval is reciprocal.
    fn non_delta_sample(&mut self, wo: Vec3, s: &rtk_kernel::abi::BsdfSample, t: &mut Tallies) {
        let (shader, g) = (self.shader, self.g);
        let w = s.weight;
        let wi = s.wi.v();
        let f = shader.eval(self.ctx, g, f3(wo), f3(wi));
        let cos = wi.z.abs();
        if s.pdf > 0.0 && !f.is_black() {
            let expect = f.scale(cos / s.pdf);
            let rel = |a: f32, b: f32| (a - b).abs() <= 1e-3 * b.abs().max(1e-3);
            if !(rel(expect.r, w.r) && rel(expect.g, w.g) && rel(expect.b, w.b)) {
                note(&mut t.weight_bad, || {
                    format!("wo {wo:?} wi {wi:?}: weight {w:?}, eval·cos/pdf {expect:?}")
                });
            }
        }
        match shader.pdf(self.ctx, g, f3(wo), f3(wi), lobe::ALL) {
            None => t.pdf_known = false,
            Some(p) if (p - s.pdf).abs() > 1e-3 * s.pdf.max(1e-3) => note(&mut t.pdf_bad, || {
                format!("wo {wo:?} wi {wi:?}: pdf() {p}, sample's pdf {}", s.pdf)
            }),
            Some(_) => {}
        }
        // Reciprocity, for reflection pairs.
        if !self.transmits && wi.z * wo.z > 0.0 {
            let back = shader.eval(self.ctx, g, f3(wi), f3(wo));
            let rel = |a: f32, b: f32| (a - b).abs() <= 1e-3 * a.abs().max(b.abs()).max(1e-6);
            if !(rel(back.r, f.r) && rel(back.g, f.g) && rel(back.b, f.b)) {
                note(&mut t.recip_bad, || {
                    format!("f(wo, wi) {f:?} but f(wi, wo) {back:?} for wo {wo:?} wi {wi:?}")
                });
            }
        }
    }

    /// ∫ pdf dω by uniform directions (4π·E\[pdf\]) against the share of
    /// non-delta samples, which is the mass the density covers.
    fn pdf_integral(&mut self, wo: Vec3, nonzero_share: f64, t: &mut Tallies) {
        let m = 4 * self.n;
        let (mut s1, mut s2) = (0.0f64, 0.0f64);
        for _ in 0..m {
            let wi = uniform_sphere([self.rng.next_f32(), self.rng.next_f32()]);
            let p = self
                .shader
                .pdf(self.ctx, self.g, f3(wo), f3(wi), lobe::ALL)
                .unwrap_or(0.0) as f64
                * 4.0
                * std::f64::consts::PI;
            s1 += p;
            s2 += p * p;
        }
        let mean = s1 / m as f64;
        let se = ((s2 / m as f64 - mean * mean).max(0.0) / m as f64).sqrt();
        if (mean - nonzero_share).abs() > 5.0 * se + 0.02 && t.integral_bad.0 {
            t.integral_bad = (
                false,
                format!(
                    "at wo {wo:?}, ∫ pdf dω = {mean:.4} ± {se:.4}, but {nonzero_share:.4} of samples are not delta"
                ),
            );
        }
    }
}

fn f3(v: Vec3) -> Float3 {
    v.into()
}

/// The checks' lines from the tallies (the density checks skipped for a
/// shader without densities, reciprocity for one that transmits).
fn push_checks(suite: &mut Suite, t: &Tallies, transmits: bool) {
    suite.push(count_check("finite", &t.nonfinite));
    suite.push(Check::new(
        "energy",
        t.energy.0,
        if t.energy.0 {
            "mean weight ≤ 1 at every direction tried".into()
        } else {
            t.energy.1.clone()
        },
    ));
    suite.push(count_check("weight-matches-eval", &t.weight_bad));
    if t.pdf_known {
        suite.push(count_check("pdf-matches-sample", &t.pdf_bad));
        suite.push(Check::new(
            "pdf-integrates",
            t.integral_bad.0,
            if t.integral_bad.0 {
                "∫ pdf dω matches the non-delta share at every direction tried".into()
            } else {
                t.integral_bad.1.clone()
            },
        ));
    } else {
        let why = "the shader reports no density (no MIS for it)";
        suite.push(Check::skip("pdf-matches-sample", why));
        suite.push(Check::skip("pdf-integrates", why));
    }
    if transmits {
        suite.push(Check::skip(
            "reciprocity",
            "the shader transmits: f(wo, wi) = f(wi, wo) does not hold across an interface",
        ));
    } else {
        suite.push(count_check("reciprocity", &t.recip_bad));
    }
}

fn count_check(name: &'static str, slot: &(u64, String)) -> Check {
    Check::new(
        name,
        slot.0 == 0,
        if slot.0 == 0 {
            "held on every sample".into()
        } else {
            format!("{} failures; first: {}", slot.0, slot.1)
        },
    )
}
