//! Spectra reduced to RGB as Mitsuba's RGB variants reduce them when they
//! read a scene (`spectrum_list_to_srgb` in its `src/core/spectrum.cpp`,
//! called from `Properties::get_texture`): the piecewise-linear spectrum is
//! integrated against the CIE 1931 curves at 1000 evenly spaced wavelengths
//! over [360, 830] nm, weighted by D65 unless it is an emission, and the
//! XYZ converted to linear sRGB. Doing it the same way (same tables, same
//! quadrature) is what makes an imported reflectance the colour Mitsuba
//! rendered with, not merely a close one.

/// Samples in each table.
const SAMPLES: usize = 95;
/// Shortest and longest wavelength of the tables, in nm.
const CIE_MIN: f64 = 360.0;
const CIE_MAX: f64 = 830.0;
/// Makes a unit spectrum integrate to a luminance of 1.
const CIE_Y_NORMALIZATION: f64 = 1.0 / 106.750_259_399_414_06;
/// Makes D65 integrate to a luminance of 1.
const D65_NORMALIZATION: f64 = 1.0 / 98.997_417_518_762_55;

/// How a spectrum is used, which decides Mitsuba's reduction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// A reflectance: weighted by D65, clipped to [0, 1].
    Reflectance,
    /// A radiance, intensity or irradiance: not weighted, only clipped at 0.
    Emission,
    /// A physical constant such as a conductor's complex index (Mitsuba's
    /// unbounded textures): a list as an emission, a uniform value as is.
    Unbounded,
}

/// RGB of a list of (wavelength in nm, value) pairs, sorted by wavelength.
/// `None` when the list is empty or not increasing.
pub fn list_to_srgb(pairs: &[(f64, f64)], role: Role) -> Option<[f64; 3]> {
    if pairs.is_empty() || pairs.windows(2).any(|w| !(w[0].0 < w[1].0)) {
        return None;
    }
    let steps = 1000;
    let (first, last) = (pairs[0].0, pairs[pairs.len() - 1].0);
    let mut xyz = [0.0f64; 3];
    for i in 0..steps {
        let w = CIE_MIN + (i as f64 / (steps - 1) as f64) * (CIE_MAX - CIE_MIN);
        if w < first || w > last {
            continue;
        }
        // The interval [w0, w1] holding w (the last one when w == last).
        let k = pairs
            .partition_point(|p| p.0 <= w)
            .clamp(1, pairs.len().max(2) - 1)
            - 1;
        let v = if pairs.len() == 1 {
            pairs[0].1
        } else {
            let ((w0, v0), (w1, v1)) = (pairs[k], pairs[k + 1]);
            ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1)
        };
        let weight = match role {
            Role::Reflectance => table(&D65, w) * D65_NORMALIZATION,
            Role::Emission | Role::Unbounded => 1.0,
        };
        let c = [table(&CIE_X, w), table(&CIE_Y, w), table(&CIE_Z, w)];
        for j in 0..3 {
            xyz[j] += c[j] * v * weight;
        }
    }
    let norm = (CIE_MAX - CIE_MIN) * CIE_Y_NORMALIZATION / steps as f64;
    let rgb = xyz_to_srgb(xyz.map(|x| x * norm));
    Some(match role {
        Role::Reflectance => rgb.map(|c| c.clamp(0.0, 1.0)),
        Role::Emission | Role::Unbounded => rgb.map(|c| c.max(0.0)),
    })
}

/// RGB of a uniform spectrum of value `v`. A reflectance stays grey; an
/// emission becomes `v · xyz_to_srgb(1, 1, 1)`, the slightly purple colour
/// a flat spectrum has against sRGB's D65 white, as Mitsuba's RGB variants
/// make it so that they match its spectral ones.
pub fn uniform_to_srgb(v: f64, role: Role) -> [f64; 3] {
    match role {
        Role::Reflectance | Role::Unbounded => [v; 3],
        Role::Emission => xyz_to_srgb([1.0; 3]).map(|c| c * v),
    }
}

/// Linear sRGB (Rec. 709 primaries, D65 white) of an XYZ colour, with
/// Mitsuba's matrix.
fn xyz_to_srgb(xyz: [f64; 3]) -> [f64; 3] {
    const M: [[f64; 3]; 3] = [
        [3.240479, -1.537150, -0.498535],
        [-0.969256, 1.875991, 0.041556],
        [0.055648, -0.204043, 1.057311],
    ];
    M.map(|r| r[0] * xyz[0] + r[1] * xyz[1] + r[2] * xyz[2])
}

/// A table linearly interpolated at wavelength `w` (0 outside the tables).
fn table(t: &[f64; SAMPLES], w: f64) -> f64 {
    if !(CIE_MIN..=CIE_MAX).contains(&w) {
        return 0.0;
    }
    let x = (w - CIE_MIN) * ((SAMPLES - 1) as f64 / (CIE_MAX - CIE_MIN));
    let i0 = (x as usize).min(SAMPLES - 2);
    let f = x - i0 as f64;
    (1.0 - f) * t[i0] + f * t[i0 + 1]
}

/// CIE 1931 x̄, 360 to 830 nm in 5 nm steps.
#[rustfmt::skip]
const CIE_X: [f64; SAMPLES] = [
    0.000129900000, 0.000232100000, 0.000414900000, 0.000741600000, 0.001368000000, 0.002236000000,
    0.004243000000, 0.007650000000, 0.014310000000, 0.023190000000, 0.043510000000, 0.077630000000,
    0.134380000000, 0.214770000000, 0.283900000000, 0.328500000000, 0.348280000000, 0.348060000000,
    0.336200000000, 0.318700000000, 0.290800000000, 0.251100000000, 0.195360000000, 0.142100000000,
    0.095640000000, 0.057950010000, 0.032010000000, 0.014700000000, 0.004900000000, 0.002400000000,
    0.009300000000, 0.029100000000, 0.063270000000, 0.109600000000, 0.165500000000, 0.225749900000,
    0.290400000000, 0.359700000000, 0.433449900000, 0.512050100000, 0.594500000000, 0.678400000000,
    0.762100000000, 0.842500000000, 0.916300000000, 0.978600000000, 1.026300000000, 1.056700000000,
    1.062200000000, 1.045600000000, 1.002600000000, 0.938400000000, 0.854449900000, 0.751400000000,
    0.642400000000, 0.541900000000, 0.447900000000, 0.360800000000, 0.283500000000, 0.218700000000,
    0.164900000000, 0.121200000000, 0.087400000000, 0.063600000000, 0.046770000000, 0.032900000000,
    0.022700000000, 0.015840000000, 0.011359160000, 0.008110916000, 0.005790346000, 0.004109457000,
    0.002899327000, 0.002049190000, 0.001439971000, 0.000999949300, 0.000690078600, 0.000476021300,
    0.000332301100, 0.000234826100, 0.000166150500, 0.000117413000, 0.000083075270, 0.000058706520,
    0.000041509940, 0.000029353260, 0.000020673830, 0.000014559770, 0.000010253980, 0.000007221456,
    0.000005085868, 0.000003581652, 0.000002522525, 0.000001776509, 0.000001251141,
];
/// CIE 1931 ȳ.
#[rustfmt::skip]
const CIE_Y: [f64; SAMPLES] = [
    0.000003917000, 0.000006965000, 0.000012390000, 0.000022020000, 0.000039000000, 0.000064000000,
    0.000120000000, 0.000217000000, 0.000396000000, 0.000640000000, 0.001210000000, 0.002180000000,
    0.004000000000, 0.007300000000, 0.011600000000, 0.016840000000, 0.023000000000, 0.029800000000,
    0.038000000000, 0.048000000000, 0.060000000000, 0.073900000000, 0.090980000000, 0.112600000000,
    0.139020000000, 0.169300000000, 0.208020000000, 0.258600000000, 0.323000000000, 0.407300000000,
    0.503000000000, 0.608200000000, 0.710000000000, 0.793200000000, 0.862000000000, 0.914850100000,
    0.954000000000, 0.980300000000, 0.994950100000, 1.000000000000, 0.995000000000, 0.978600000000,
    0.952000000000, 0.915400000000, 0.870000000000, 0.816300000000, 0.757000000000, 0.694900000000,
    0.631000000000, 0.566800000000, 0.503000000000, 0.441200000000, 0.381000000000, 0.321000000000,
    0.265000000000, 0.217000000000, 0.175000000000, 0.138200000000, 0.107000000000, 0.081600000000,
    0.061000000000, 0.044580000000, 0.032000000000, 0.023200000000, 0.017000000000, 0.011920000000,
    0.008210000000, 0.005723000000, 0.004102000000, 0.002929000000, 0.002091000000, 0.001484000000,
    0.001047000000, 0.000740000000, 0.000520000000, 0.000361100000, 0.000249200000, 0.000171900000,
    0.000120000000, 0.000084800000, 0.000060000000, 0.000042400000, 0.000030000000, 0.000021200000,
    0.000014990000, 0.000010600000, 0.000007465700, 0.000005257800, 0.000003702900, 0.000002607800,
    0.000001836600, 0.000001293400, 0.000000910930, 0.000000641530, 0.000000451810,
];
/// CIE 1931 z̄.
#[rustfmt::skip]
const CIE_Z: [f64; SAMPLES] = [
    0.000606100000, 0.001086000000, 0.001946000000, 0.003486000000, 0.006450001000, 0.010549990000,
    0.020050010000, 0.036210000000, 0.067850010000, 0.110200000000, 0.207400000000, 0.371300000000,
    0.645600000000, 1.039050100000, 1.385600000000, 1.622960000000, 1.747060000000, 1.782600000000,
    1.772110000000, 1.744100000000, 1.669200000000, 1.528100000000, 1.287640000000, 1.041900000000,
    0.812950100000, 0.616200000000, 0.465180000000, 0.353300000000, 0.272000000000, 0.212300000000,
    0.158200000000, 0.111700000000, 0.078249990000, 0.057250010000, 0.042160000000, 0.029840000000,
    0.020300000000, 0.013400000000, 0.008749999000, 0.005749999000, 0.003900000000, 0.002749999000,
    0.002100000000, 0.001800000000, 0.001650001000, 0.001400000000, 0.001100000000, 0.001000000000,
    0.000800000000, 0.000600000000, 0.000340000000, 0.000240000000, 0.000190000000, 0.000100000000,
    0.000049999990, 0.000030000000, 0.000020000000, 0.000010000000, 0.000000000000, 0.000000000000,
    0.000000000000, 0.000000000000, 0.000000000000, 0.000000000000, 0.000000000000, 0.000000000000,
    0.000000000000, 0.000000000000, 0.000000000000, 0.000000000000, 0.000000000000, 0.000000000000,
    0.000000000000, 0.000000000000, 0.000000000000, 0.000000000000, 0.000000000000, 0.000000000000,
    0.000000000000, 0.000000000000, 0.000000000000, 0.000000000000, 0.000000000000, 0.000000000000,
    0.000000000000, 0.000000000000, 0.000000000000, 0.000000000000, 0.000000000000, 0.000000000000,
    0.000000000000, 0.000000000000, 0.000000000000, 0.000000000000, 0.000000000000,
];
/// The CIE D65 illuminant, relative to its power at 560 nm.
#[rustfmt::skip]
const D65: [f64; SAMPLES] = [
    46.6383, 49.3637, 52.0891, 51.0323, 49.9755, 52.3118,
    54.6482, 68.7015, 82.7549, 87.1204, 91.486, 92.4589,
    93.4318, 90.057, 86.6823, 95.7736, 104.865, 110.936,
    117.008, 117.41, 117.812, 116.336, 114.861, 115.392,
    115.923, 112.367, 108.811, 109.082, 109.354, 108.578,
    107.802, 106.296, 104.79, 106.239, 107.689, 106.047,
    104.405, 104.225, 104.046, 102.023, 100.0, 98.1671,
    96.3342, 96.0611, 95.788, 92.2368, 88.6856, 89.3459,
    90.0062, 89.8026, 89.5991, 88.6489, 87.6987, 85.4936,
    83.2886, 83.4939, 83.6992, 81.863, 80.0268, 80.1207,
    80.2146, 81.2462, 82.2778, 80.281, 78.2842, 74.0027,
    69.7213, 70.6652, 71.6091, 72.979, 74.349, 67.9765,
    61.604, 65.7448, 69.8856, 72.4863, 75.087, 69.3398,
    63.5927, 55.0054, 46.4182, 56.6118, 66.8054, 65.0941,
    63.3828, 63.8434, 64.304, 61.8779, 59.4519, 55.7054,
    51.959, 54.6998, 57.4406, 58.8765, 60.3125,
];

#[cfg(test)]
mod tests {
    use super::*;

    /// Mitsuba 3.9.1's own `mi.spectrum_list_to_srgb` (scalar_rgb) on the
    /// same lists: bounded and D65-weighted for a reflectance, neither for
    /// an emission.
    /// A wavelength list, its role and Mitsuba's RGB for it.
    type Case = (&'static [(f64, f64)], Role, [f64; 3]);

    #[test]
    fn matches_mitsubas_reduction() {
        let cases: [Case; 4] = [
            (
                &[(400.0, 0.78), (500.0, 0.78), (600.0, 0.78), (700.0, 0.78)],
                Role::Reflectance,
                [0.776368, 0.779809, 0.776029],
            ),
            (
                &[(400.0, 0.0), (500.0, 8.0), (600.0, 15.6), (700.0, 18.4)],
                Role::Emission,
                [20.7108, 10.8546, 2.77115],
            ),
            (
                &[(450.0, 0.2), (550.0, 0.9), (650.0, 0.4)],
                Role::Reflectance,
                [0.518188, 0.815344, 0.113643],
            ),
            (
                &[(380.0, 1.0), (780.0, 1.0)],
                Role::Reflectance,
                [0.998931, 0.998911, 0.998545],
            ),
        ];
        for (pairs, role, want) in cases {
            let got = list_to_srgb(pairs, role).unwrap();
            for c in 0..3 {
                assert!(
                    (got[c] - want[c]).abs() <= 2e-5 * want[c].abs().max(1.0),
                    "{pairs:?} {role:?}: {got:?} != {want:?}"
                );
            }
        }
    }

    #[test]
    fn a_flat_emission_is_mitsubas_purple() {
        let got = uniform_to_srgb(2.0, Role::Emission);
        let want = [1.20479, 0.948291, 0.908916].map(|c| 2.0 * c);
        for c in 0..3 {
            assert!((got[c] - want[c]).abs() < 1e-5, "{got:?}");
        }
        assert_eq!(uniform_to_srgb(0.3, Role::Reflectance), [0.3; 3]);
    }

    #[test]
    fn unsorted_or_empty_lists_are_refused() {
        assert_eq!(list_to_srgb(&[], Role::Emission), None);
        assert_eq!(
            list_to_srgb(&[(500.0, 1.0), (400.0, 1.0)], Role::Emission),
            None
        );
    }
}
