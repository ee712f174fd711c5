//! Conveniences on the ABI's plain values: glam conversions, constructors and
//! the small amount of arithmetic plugins need. Nothing here changes a layout.

use crate::*;
use glam::Vec3;

impl Float3 {
    /// From components (a `const fn`, unlike the glam conversion).
    #[inline]
    pub const fn new(x: f32, y: f32, z: f32) -> Self {
        Self { x, y, z }
    }
    /// As a glam vector.
    #[inline]
    pub fn v(self) -> Vec3 {
        Vec3::new(self.x, self.y, self.z)
    }
    /// As an array.
    #[inline]
    pub fn to_array(self) -> [f32; 3] {
        [self.x, self.y, self.z]
    }
    /// All components finite.
    #[inline]
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }
}

impl From<Vec3> for Float3 {
    #[inline]
    fn from(v: Vec3) -> Self {
        Self::new(v.x, v.y, v.z)
    }
}

impl From<Float3> for Vec3 {
    #[inline]
    fn from(v: Float3) -> Self {
        v.v()
    }
}

impl From<&Float3> for Float3 {
    #[inline]
    fn from(v: &Float3) -> Self {
        *v
    }
}

impl From<&Vec3> for Float3 {
    #[inline]
    fn from(v: &Vec3) -> Self {
        Self::new(v.x, v.y, v.z)
    }
}

impl From<[f32; 3]> for Float3 {
    #[inline]
    fn from(a: [f32; 3]) -> Self {
        Self::new(a[0], a[1], a[2])
    }
}

impl Color {
    /// Black.
    pub const BLACK: Color = Color::new(0.0, 0.0, 0.0);
    /// From linear RGB components.
    #[inline]
    pub const fn new(r: f32, g: f32, b: f32) -> Self {
        Self { r, g, b, w: 0.0 }
    }
    /// A grey level.
    #[inline]
    pub const fn splat(v: f32) -> Self {
        Self::new(v, v, v)
    }
    /// From an array.
    #[inline]
    pub fn from_array(a: [f32; 3]) -> Self {
        Self::new(a[0], a[1], a[2])
    }
    /// As an array.
    #[inline]
    pub fn to_array(self) -> [f32; 3] {
        [self.r, self.g, self.b]
    }
    /// Componentwise product.
    #[inline]
    pub fn times(self, o: Color) -> Color {
        Color {
            r: self.r * o.r,
            g: self.g * o.g,
            b: self.b * o.b,
            w: self.w * o.w,
        }
    }
    /// Every component times `s`.
    #[inline]
    pub fn scale(self, s: f32) -> Color {
        Color {
            r: self.r * s,
            g: self.g * s,
            b: self.b * s,
            w: self.w * s,
        }
    }
    /// Componentwise sum (light from several paths adds).
    #[inline]
    pub fn plus(self, o: Color) -> Color {
        Color {
            r: self.r + o.r,
            g: self.g + o.g,
            b: self.b + o.b,
            w: self.w + o.w,
        }
    }
    /// True when every component is zero.
    #[inline]
    pub fn is_black(self) -> bool {
        self.r == 0.0 && self.g == 0.0 && self.b == 0.0 && self.w == 0.0
    }
    /// All components finite.
    #[inline]
    pub fn is_finite(self) -> bool {
        self.r.is_finite() && self.g.is_finite() && self.b.is_finite() && self.w.is_finite()
    }
}

/// The smaller of two values by comparison, not `f32::min`: an empty box's
/// infinities behave and a NaN never replaces a number (the second argument
/// wins only when it compares smaller).
#[inline]
fn lo(a: f32, b: f32) -> f32 {
    if b < a {
        b
    } else {
        a
    }
}

/// The larger of two values, as [`lo`].
#[inline]
fn hi(a: f32, b: f32) -> f32 {
    if b > a {
        b
    } else {
        a
    }
}

impl Bounds3 {
    /// The empty box (min = +inf, max = -inf): the identity of `union`.
    pub const EMPTY: Bounds3 = Bounds3 {
        min: Float3::new(f32::INFINITY, f32::INFINITY, f32::INFINITY),
        max: Float3::new(f32::NEG_INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY),
    };
    /// From corners.
    #[inline]
    pub fn new(min: Vec3, max: Vec3) -> Self {
        Self {
            min: min.into(),
            max: max.into(),
        }
    }
    /// Smallest box containing both.
    #[inline]
    pub fn union(self, o: Bounds3) -> Bounds3 {
        // Comparisons rather than f32::min, so that an empty box
        // (infinities) behaves and a NaN never poisons the result.
        Bounds3 {
            min: Float3::new(
                lo(self.min.x, o.min.x),
                lo(self.min.y, o.min.y),
                lo(self.min.z, o.min.z),
            ),
            max: Float3::new(
                hi(self.max.x, o.max.x),
                hi(self.max.y, o.max.y),
                hi(self.max.z, o.max.z),
            ),
        }
    }
    /// Grow to contain a point.
    #[inline]
    pub fn include(self, p: Vec3) -> Bounds3 {
        self.union(Bounds3::new(p, p))
    }
    /// True when the box contains no point.
    #[inline]
    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }
    /// The eight corners.
    pub fn corners(&self) -> [Vec3; 8] {
        let (a, b) = (self.min.v(), self.max.v());
        std::array::from_fn(|i| {
            Vec3::new(
                if i & 1 == 0 { a.x } else { b.x },
                if i & 2 == 0 { a.y } else { b.y },
                if i & 4 == 0 { a.z } else { b.z },
            )
        })
    }
}

impl Default for Bounds3 {
    fn default() -> Self {
        Bounds3::EMPTY
    }
}

impl Ray {
    /// A ray over `(0, inf)` at time 0, generation 0.
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self {
            origin: origin.into(),
            dir: dir.into(),
            t_min: 0.0,
            t_max: f32::INFINITY,
            time: 0.0,
            generation: 0,
        }
    }
    /// Point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin.v() + self.dir.v() * t
    }
    /// Is `t` an acceptable hit for this ray: `t_min < t < t_max` and finite.
    /// Written so that a NaN is never accepted.
    #[inline]
    pub fn accepts(&self, t: f32) -> bool {
        t > self.t_min && t < self.t_max && t.is_finite()
    }
}

impl Default for Hit {
    fn default() -> Self {
        Self::new()
    }
}

impl Hit {
    /// No hit yet.
    #[inline]
    pub fn new() -> Self {
        Self {
            t: f32::INFINITY,
            depth: 0,
            uv: [0.0, 0.0],
            stack: [0; HIT_STACK_DEPTH],
        }
    }
    /// No hit yet, for a record used again: only `t` and `depth` are reset.
    /// Entries at `depth` and beyond are stale and never read (a level
    /// writes its entry when it accepts a hit, before anyone reads it), so
    /// a tracer that keeps one record for many rays skips zeroing the stack.
    #[inline]
    pub fn reset(&mut self) {
        self.t = f32::INFINITY;
        self.depth = 0;
    }
    /// What the object at `level` chose: a child slot or a primitive id.
    #[inline]
    pub fn at(&self, level: u32) -> u32 {
        self.stack[level as usize]
    }
    /// Record a primitive hit at `level` (leaf objects): sets `t`, the
    /// primitive, the leaf's two words and `depth`.
    #[inline]
    pub fn record_leaf(&mut self, level: u32, t: f32, prim: u32, uv: [f32; 2]) {
        self.t = t;
        self.stack[level as usize] = prim;
        self.uv = uv;
        self.depth = level + 1;
    }
    /// Record, at `level`, that child `index` accepted the hit now in `self`
    /// (aggregates, after the child returned true).
    #[inline]
    pub fn record_child(&mut self, level: u32, index: u32) {
        self.stack[level as usize] = index;
    }
}

impl LocalGeom {
    /// Nothing filled, no shader.
    pub const EMPTY: LocalGeom = LocalGeom {
        p: Float3::new(0.0, 0.0, 0.0),
        p_err: Float3::new(0.0, 0.0, 0.0),
        ng: Float3::new(0.0, 0.0, 1.0),
        ns: Float3::new(0.0, 0.0, 1.0),
        dpdu: Float3::new(1.0, 0.0, 0.0),
        dpdv: Float3::new(0.0, 1.0, 0.0),
        dndu: Float3::new(0.0, 0.0, 0.0),
        dndv: Float3::new(0.0, 0.0, 0.0),
        uv: [0.0, 0.0],
        shader: NONE_ID,
        light: NONE_ID,
        instance: NONE_ID,
        prim: 0,
        filled: 0,
    };
}

impl Default for LocalGeom {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl InstanceData {
    /// No bindings.
    pub const NONE: InstanceData = InstanceData {
        shader: NONE_ID,
        light: NONE_ID,
        id: NONE_ID,
    };
    /// Apply these bindings to a child's local geometry where no deeper
    /// instance bound one: the innermost binding wins.
    #[inline]
    pub fn bind(&self, g: &mut LocalGeom) {
        if g.shader == NONE_ID {
            g.shader = self.shader;
        }
        if g.light == NONE_ID {
            g.light = self.light;
        }
        if g.instance == NONE_ID {
            g.instance = self.id;
        }
    }
}

impl Interior {
    /// The point is outside.
    pub const OUTSIDE: Interior = Interior(0);
    /// The point is inside.
    pub const INSIDE: Interior = Interior(1);
    /// The object has no interior to be inside of (an open surface, a flat
    /// shape, a class that does not say): neither inside nor outside.
    pub const NONE: Interior = Interior(2);

    /// Inside.
    #[inline]
    pub fn is_inside(self) -> bool {
        self == Self::INSIDE
    }

    /// A yes-or-no answer as an [`Interior`].
    #[inline]
    pub fn from_bool(inside: bool) -> Self {
        if inside {
            Self::INSIDE
        } else {
            Self::OUTSIDE
        }
    }

    /// The answer of a union of objects (aggregates): inside if any member
    /// is; else outside if any member has an interior; else none.
    #[inline]
    pub fn union(self, o: Interior) -> Interior {
        if self.is_inside() || o.is_inside() {
            Self::INSIDE
        } else if self == Self::OUTSIDE || o == Self::OUTSIDE {
            Self::OUTSIDE
        } else {
            Self::NONE
        }
    }
}

impl<T> Span<T> {
    /// Borrow a slice for a call.
    #[inline]
    pub fn of(s: &[T]) -> Self {
        Span {
            ptr: s.as_ptr(),
            len: s.len(),
        }
    }
    /// The slice again.
    ///
    /// # Safety
    /// `ptr` must point at `len` initialised values valid for `'a` (or `len` be 0).
    #[inline]
    pub unsafe fn as_slice<'a>(self) -> &'a [T] {
        if self.len == 0 || self.ptr.is_null() {
            &[]
        } else {
            // SAFETY: guaranteed by the caller.
            unsafe { std::slice::from_raw_parts(self.ptr, self.len) }
        }
    }
}

impl<T> SpanMut<T> {
    /// Borrow a mutable slice for a call.
    #[inline]
    pub fn of(s: &mut [T]) -> Self {
        SpanMut {
            ptr: s.as_mut_ptr(),
            len: s.len(),
        }
    }
    /// The mutable slice again.
    ///
    /// # Safety
    /// `ptr` must point at `len` initialised values, valid and exclusive for
    /// `'a` (or `len` be 0).
    #[inline]
    pub unsafe fn as_mut_slice<'a>(self) -> &'a mut [T] {
        if self.len == 0 || self.ptr.is_null() {
            &mut []
        } else {
            // SAFETY: guaranteed by the caller.
            unsafe { std::slice::from_raw_parts_mut(self.ptr, self.len) }
        }
    }
}

impl Affine3x4 {
    /// From glam's f64 affine (object to parent).
    pub fn from_daffine(m: &glam::DAffine3) -> Self {
        let (c, t) = (m.matrix3, m.translation);
        Affine3x4 {
            rows: [
                [c.x_axis.x, c.y_axis.x, c.z_axis.x, t.x],
                [c.x_axis.y, c.y_axis.y, c.z_axis.y, t.y],
                [c.x_axis.z, c.y_axis.z, c.z_axis.z, t.z],
            ],
        }
    }

    /// As glam's f64 affine.
    pub fn to_daffine(&self) -> glam::DAffine3 {
        let r = &self.rows;
        glam::DAffine3::from_mat3_translation(
            glam::DMat3::from_cols(
                glam::DVec3::new(r[0][0], r[1][0], r[2][0]),
                glam::DVec3::new(r[0][1], r[1][1], r[2][1]),
                glam::DVec3::new(r[0][2], r[1][2], r[2][2]),
            ),
            glam::DVec3::new(r[0][3], r[1][3], r[2][3]),
        )
    }
}

impl BoundSphere {
    /// Bounds nothing: no ray meets it, and it is the identity of the
    /// spheres' union (`rtk_geom::SphereVolume::union`, which this crate
    /// cannot link to).
    pub const EMPTY: BoundSphere = BoundSphere {
        center: Float3 {
            x: 0.0,
            y: 0.0,
            z: 0.0,
        },
        radius: -1.0,
    };

    /// Whether it bounds nothing.
    pub fn is_empty(&self) -> bool {
        !(self.radius >= 0.0)
    }
}

impl SlabBounds {
    /// Bounds nothing.
    pub const EMPTY: SlabBounds = SlabBounds {
        lo: [f32::INFINITY; SLAB_COUNT],
        hi: [f32::NEG_INFINITY; SLAB_COUNT],
    };

    /// Whether it bounds nothing.
    pub fn is_empty(&self) -> bool {
        (0..SLAB_COUNT).any(|k| !(self.lo[k] <= self.hi[k]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_accepts_is_open_and_nan_false() {
        let r = Ray::new(Vec3::ZERO, Vec3::Z);
        assert!(!r.accepts(0.0));
        assert!(r.accepts(1e-30));
        assert!(!r.accepts(f32::INFINITY));
        assert!(!r.accepts(f32::NAN));
    }

    #[test]
    fn affine_rows_round_trip() {
        let m = glam::DAffine3::from_scale_rotation_translation(
            glam::DVec3::new(1.0, 2.0, 3.0),
            glam::DQuat::from_rotation_y(0.3),
            glam::DVec3::new(4.0, 5.0, 6.0),
        );
        let a = Affine3x4::from_daffine(&m);
        assert_eq!(a.rows[0][3], 4.0);
        assert_eq!(a.to_daffine(), m);
    }

    #[test]
    fn empty_bounds_union_identity() {
        let b = Bounds3::new(Vec3::ONE, Vec3::splat(2.0));
        assert_eq!(Bounds3::EMPTY.union(b), b);
        assert!(Bounds3::EMPTY.is_empty());
        assert!(!b.is_empty());
    }
}
