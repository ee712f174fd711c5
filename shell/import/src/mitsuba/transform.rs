//! Mitsuba's `<transform>`: its steps as written (so the translation can
//! emit rtk's readable `transform = [{ scale = ... }, ...]`) and their
//! composition in f64, with the conventions of Mitsuba's `Transform`
//! (`include/mitsuba/core/transform.h`): `rotate` is right-handed about its
//! axis, `lookat` puts the camera's +z on the target and +x to the left.

/// One step, in rtk's terms.
#[derive(Debug, Clone, PartialEq)]
pub enum Step {
    /// Add a vector.
    Translate([f64; 3]),
    /// Scale per axis.
    Scale([f64; 3]),
    /// Rotate `angle` degrees about `axis` (right-handed).
    Rotate {
        /// The axis (not necessarily unit).
        axis: [f64; 3],
        /// Degrees.
        angle: f64,
    },
    /// A general affine matrix, row-major, last row 0 0 0 1.
    Matrix([f64; 16]),
}

/// A composed transform and the steps it was made of.
#[derive(Debug, Clone, PartialEq)]
pub struct Transform {
    /// Row-major 4x4.
    pub m: [[f64; 4]; 4],
    /// The steps, first applied first.
    pub steps: Vec<Step>,
}

type M4 = [[f64; 4]; 4];

fn mul(a: &M4, b: &M4) -> M4 {
    let mut r = [[0.0; 4]; 4];
    for (i, row) in r.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    r
}

const ID: M4 = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalize(a: [f64; 3]) -> Option<[f64; 3]> {
    let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    (l > 0.0 && l.is_finite()).then(|| [a[0] / l, a[1] / l, a[2] / l])
}

impl Transform {
    /// No change.
    pub fn identity() -> Transform {
        Transform {
            m: ID,
            steps: Vec::new(),
        }
    }

    fn then(&mut self, m: M4, step: Step) {
        self.m = mul(&m, &self.m);
        self.steps.push(step);
    }

    /// Then translate by `v`.
    pub fn translate(&mut self, v: [f64; 3]) {
        let mut m = ID;
        for k in 0..3 {
            m[k][3] = v[k];
        }
        self.then(m, Step::Translate(v));
    }

    /// Then scale by `s` per axis.
    pub fn scale(&mut self, s: [f64; 3]) {
        let mut m = ID;
        for k in 0..3 {
            m[k][k] = s[k];
        }
        self.then(m, Step::Scale(s));
    }

    /// Then rotate `angle` degrees about `axis` (Rodrigues' formula).
    pub fn rotate(&mut self, axis: [f64; 3], angle: f64) -> Result<(), String> {
        let [x, y, z] = normalize(axis).ok_or("the axis is zero")?;
        let (s, c) = angle.to_radians().sin_cos();
        let t = 1.0 - c;
        let m = [
            [t * x * x + c, t * x * y - s * z, t * x * z + s * y, 0.0],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x, 0.0],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ];
        self.then(m, Step::Rotate { axis, angle });
        Ok(())
    }

    /// Then apply a matrix of 16 (row-major 4x4) or 9 (3x3) numbers.
    pub fn matrix(&mut self, v: &[f64]) -> Result<(), String> {
        let mut m = ID;
        match v.len() {
            16 => {
                for (k, x) in v.iter().enumerate() {
                    m[k / 4][k % 4] = *x;
                }
                if m[3] != [0.0, 0.0, 0.0, 1.0] {
                    return Err(
                        "a projective matrix (last row not 0 0 0 1): rtk transforms are affine"
                            .into(),
                    );
                }
            }
            9 => {
                for (k, x) in v.iter().enumerate() {
                    m[k / 3][k % 3] = *x;
                }
            }
            n => return Err(format!("{n} numbers: expected 16 (4x4) or 9 (3x3)")),
        }
        self.then(m, Step::Matrix(flat(&m)));
        Ok(())
    }

    /// Then Mitsuba's `lookat`: +z towards `target`, +y towards `up`
    /// (made orthogonal), +x = up × dir (the camera's left).
    pub fn look_at(
        &mut self,
        origin: [f64; 3],
        target: [f64; 3],
        up: Option<[f64; 3]>,
    ) -> Result<(), String> {
        let dir = normalize(sub(target, origin)).ok_or("origin and target coincide")?;
        let up = match up {
            Some(u) => u,
            // Mitsuba: any direction perpendicular to dir.
            None => any_perpendicular(dir),
        };
        let left = normalize(cross(up, dir)).ok_or("`up` is parallel to the view direction")?;
        let new_up = cross(dir, left);
        let mut m = ID;
        for k in 0..3 {
            m[k][0] = left[k];
            m[k][1] = new_up[k];
            m[k][2] = dir[k];
            m[k][3] = origin[k];
        }
        self.then(m, Step::Matrix(flat(&m)));
        Ok(())
    }

    /// The image of point `p`.
    pub fn point(&self, p: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| {
            self.m[i][0] * p[0] + self.m[i][1] * p[1] + self.m[i][2] * p[2] + self.m[i][3]
        })
    }

    /// The image of direction `v`.
    pub fn vector(&self, v: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| self.m[i][0] * v[0] + self.m[i][1] * v[1] + self.m[i][2] * v[2])
    }

    /// Determinant of the linear part.
    pub fn det(&self) -> f64 {
        let m = &self.m;
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    }
}

/// A unit vector perpendicular to unit `d` (Duff et al.'s frame).
fn any_perpendicular(d: [f64; 3]) -> [f64; 3] {
    let sign = 1f64.copysign(d[2]);
    let a = -1.0 / (sign + d[2]);
    let b = d[0] * d[1] * a;
    [b, sign + d[1] * d[1] * a, -d[1]]
}

fn flat(m: &M4) -> [f64; 16] {
    std::array::from_fn(|k| m[k / 4][k % 4])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        (0..3).all(|k| (a[k] - b[k]).abs() < 1e-12)
    }

    #[test]
    fn steps_apply_in_order() {
        // Mitsuba: <scale value="0.1"/><translate value="0,0,1"/>.
        let mut t = Transform::identity();
        t.scale([0.1; 3]);
        t.translate([0.0, 0.0, 1.0]);
        assert!(close(t.point([1.0, 0.0, 0.0]), [0.1, 0.0, 1.0]));
        assert_eq!(t.steps.len(), 2);
    }

    #[test]
    fn rotation_is_right_handed() {
        let mut t = Transform::identity();
        t.rotate([0.0, 0.0, 2.0], 90.0).unwrap();
        assert!(close(t.point([1.0, 0.0, 0.0]), [0.0, 1.0, 0.0]));
    }

    #[test]
    fn lookat_puts_z_on_the_target_and_x_to_the_left() {
        let mut t = Transform::identity();
        t.look_at([0.0, -5.0, 1.0], [0.0, 0.0, 0.5], Some([0.0, 0.0, 1.0]))
            .unwrap();
        assert!(close(t.point([0.0; 3]), [0.0, -5.0, 1.0]));
        let d = t.vector([0.0, 0.0, 1.0]);
        let want = normalize([0.0, 5.0, -0.5]).unwrap();
        assert!(close(d, want));
        // Looking along +y with z up, the left is -x.
        assert!(t.vector([1.0, 0.0, 0.0])[0] < -0.99);
        assert!(t.det() > 0.0);
    }
}
