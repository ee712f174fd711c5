#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    op: String,
}

#[derive(Clone, Copy, PartialEq)]
enum Op {
    Union,
    Intersection,
    Difference,
}

impl Op {
    #[inline]
    fn inside(self, a: bool, b: bool) -> bool {
        match self {
            Op::Union => a || b,
            Op::Intersection => a && b,
            Op::Difference => a && !b,
        }
    }
}

struct Csg {
    op: Op,
    children: Vec<Child>,
}

/// Most crossings walked per child and query: a bound on the work, not a
/// limit any closed scene object reaches.
const MAX_CROSSINGS: u32 = 64;

/// One child's walk along the ray: its next crossing and whether the ray is
/// inside it before that crossing.
struct Walk {
    hit: Hit,
    found: bool,
    entering: bool,
    inside: bool,
    steps: u32,
}

impl Plugin for Csg {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        let op = match p.op.as_str() {
            "union" => Op::Union,
            "intersection" => Op::Intersection,
            "difference" => Op::Difference,
            other => {
                return Err(PluginError::key(
                    "op",
                    format!("unknown operation `{other}`: use union, intersection or difference"),
                ))
            }
        };
        Ok(Csg {
            op,
            children: Vec::new(),
        })
    }
}

impl Csg {
    /// The child's next crossing strictly after `after`: its hit, and
    /// whether the ray enters there (the geometric normal faces the ray).
    fn next(&self, ctx: &mut TraceCtx, c: usize, ray: &Ray, after: f32, level: u32, w: &mut Walk) {
        w.found = false;
        if w.steps >= MAX_CROSSINGS {
            return;
        }
        w.steps += 1;
        let child = &self.children[c];
        let r = Ray {
            t_min: after,
            t_max: f32::INFINITY,
            ..*ray
        };
        let mut h = Hit::new();
        if !child.intersect(ctx, &r, &mut h, level + 1) {
            return;
        }
        let mut g = LocalGeom::EMPTY;
        child.local_geom(ctx, &r, &h, level + 1, geom_mask::GEOMETRIC_NORMAL, &mut g);
        w.entering = g.ng.v().dot(ray.dir.v()) < 0.0;
        w.hit = h;
        w.found = true;
    }

    /// The first crossing in (t_min, t_max) where membership in the result
    /// changes: (t, which child, its hit).
    fn first(&self, ctx: &mut TraceCtx, ray: &Ray, level: u32) -> Option<(usize, Hit)> {
        let mut w = [0, 1].map(|_| Walk {
            hit: Hit::new(),
            found: false,
            entering: false,
            inside: false,
            steps: 0,
        });
        // Where the ray starts: inside a child when its first crossing
        // after the origin is an exit.
        for (c, walk) in w.iter_mut().enumerate() {
            self.next(ctx, c, ray, 0.0f32.min(ray.t_min), level, walk);
            walk.inside = walk.found && !walk.entering;
        }
        loop {
            let t = [0, 1].map(|c| {
                if w[c].found {
                    w[c].hit.t
                } else {
                    f32::INFINITY
                }
            });
            let t_now = t[0].min(t[1]);
            if !(t_now < ray.t_max) {
                return None;
            }
            let before = self.op.inside(w[0].inside, w[1].inside);
            // Crossings at the same t apply together (the tie rule).
            let moves = [t[0] == t_now, t[1] == t_now];
            let after = self
                .op
                .inside(w[0].inside ^ moves[0], w[1].inside ^ moves[1]);
            if before != after && t_now > ray.t_min {
                let c = if moves[0] { 0 } else { 1 };
                return Some((c, w[c].hit));
            }
            for c in 0..2 {
                if moves[c] {
                    w[c].inside = !w[c].inside;
                    let at = w[c].hit.t;
                    let mut walk = std::mem::replace(
                        &mut w[c],
                        Walk {
                            hit: Hit::new(),
                            found: false,
                            entering: false,
                            inside: false,
                            steps: 0,
                        },
                    );
                    let inside = walk.inside;
                    self.next(ctx, c, ray, at, level, &mut walk);
                    walk.inside = inside;
                    w[c] = walk;
                }
            }
        }
    }
}

impl Object for Csg {
    /// The boolean of the children's interiors; none when a child has no
    /// interior to combine (CSG's children must be closed).
    fn in_interior(&self, ctx: &mut TraceCtx, p: glam::Vec3, time: f32) -> Interior {
        let [a, b] = [0, 1].map(|i| match self.children.get(i) {
            Some(c) => c.in_interior(ctx, p, time),
            None => Interior::NONE,
        });
        if a == Interior::NONE || b == Interior::NONE {
            return Interior::NONE;
        }
        Interior::from_bool(self.op.inside(a.is_inside(), b.is_inside()))
    }

    fn add_child(&mut self, child: Child) -> Result<(), PluginError> {
        if self.children.len() == 2 {
            return Err(PluginError::key(
                "children",
                "a csg node takes exactly two children",
            ));
        }
        self.children.push(child);
        Ok(())
    }

    fn prepare(&mut self, _env: &Prepare) -> Result<(), PluginError> {
        if self.children.len() != 2 {
            return Err(PluginError::key(
                "children",
                "a csg node needs two children: A, then B",
            ));
        }
        Ok(())
    }

    fn bounds(&self, t0: f32, t1: f32) -> Bounds3 {
        let b = |c: usize| {
            self.children[c].bounds(t0, t1).unwrap_or(Bounds3::new(
                glam::Vec3::splat(-f32::MAX),
                glam::Vec3::splat(f32::MAX),
            ))
        };
        match self.op {
            Op::Union => b(0).union(b(1)),
            Op::Difference => b(0),
            Op::Intersection => {
                let (a, c) = (b(0), b(1));
                let lo = a.min.v().max(c.min.v());
                let hi = a.max.v().min(c.max.v());
                if lo.cmple(hi).all() {
                    Bounds3::new(lo, hi)
                } else {
                    Bounds3::EMPTY
                }
            }
        }
    }

    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        let Some((c, h)) = self.first(ctx, ray, level) else {
            return false;
        };
        // The child's path, below this level, as the child wrote it.
        let depth = h.depth as usize;
        hit.stack[level as usize + 1..depth].copy_from_slice(&h.stack[level as usize + 1..depth]);
        hit.t = h.t;
        hit.depth = h.depth;
        hit.uv = h.uv;
        // Which child (whether its normals flip follows from it).
        hit.record_child(level, c as u32);
        true
    }

    fn local_geom(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        hit: &Hit,
        level: u32,
        mask: u32,
        out: &mut LocalGeom,
    ) {
        let i = hit.at(level) as usize;
        let Some(c) = self.children.get(i) else {
            return;
        };
        c.local_geom(ctx, ray, hit, level + 1, mask, out);
        // A difference's second child bounds the result from inside: its
        // normals turn outward of the result.
        if self.op == Op::Difference && i == 1 {
            out.ng = (-out.ng.v()).into();
            out.ns = (-out.ns.v()).into();
            out.dpdv = (-out.dpdv.v()).into();
        }
    }
}

rtk_kernel::export_object!(Csg, class = "csg", doc = include_str!("../README.md"));
