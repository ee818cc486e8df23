//! Small numeric helpers shared by the pipeline, all through `libm` so that
//! every target computes bit-identical results.

/// A point or displacement in 3D (metres, colour camera frame: x right, y down, z forward).
pub type Vec3 = nalgebra::Vector3<f64>;

/// A point in the image plane (pixels, x right, y down).
pub type Vec2 = nalgebra::Vector2<f64>;

/// Lengths below this (metres or pixels) are treated as zero when dividing.
pub const LENGTH_EPSILON: f64 = 1e-12;

/// `e^x`, the same on every target.
#[inline]
pub fn exp(x: f64) -> f64 {
    libm::exp(x)
}

/// `e^-x` for `x` in `[0, 700]`, several times faster than [`exp`] and
/// within 1e-13 of it: `64 x log2(e) = k + d` with `k` an integer and
/// `|d| <= 1/2`, so `e^-x = 2^-(k div 64) 2^-(k mod 64)/64 e^(-d ln2 / 64)`:
/// a shift of the exponent, a 64-entry table and a degree-6 polynomial on
/// `|r| < 0.0055`. Only `+`, `*` and bit operations, so every target computes
/// the same value. Outside the range it falls back to [`exp`].
#[inline]
pub fn exp_neg(x: f64) -> f64 {
    if !(0.0..=700.0).contains(&x) {
        return exp(-x);
    }
    let t = x * (64.0 * core::f64::consts::LOG2_E);
    // Adding 1.5 * 2^52 rounds t to the nearest integer, which then sits in
    // the low mantissa bits (cheaper than a saturating float-to-int cast).
    const ROUNDER: f64 = 6_755_399_441_055_744.0;
    let shifted = t + ROUNDER;
    let k = (shifted.to_bits() & 0xF_FFFF_FFFF) as i64;
    let r = ((shifted - ROUNDER) - t) * (core::f64::consts::LN_2 / 64.0);
    let p = 1.0
        + r * (1.0
            + r * (0.5
                + r * (1.0 / 6.0 + r * (1.0 / 24.0 + r * (1.0 / 120.0 + r * (1.0 / 720.0))))));
    let scale = f64::from_bits(((1023 - (k >> 6)) as u64) << 52);
    EXP2_NEG_SIXTYFOURTHS[(k & 63) as usize] * p * scale
}

/// `2^(-j/64)` for `j` in `0..64`.
#[allow(clippy::excessive_precision, clippy::approx_constant)]
const EXP2_NEG_SIXTYFOURTHS: [f64; 64] = [
    1.0,
    0.9892280131939755,
    0.9785720620877001,
    0.9680308967461472,
    0.9576032806985737,
    0.9472879907934828,
    0.93708381705515,
    0.9269895625416927,
    0.9170040432046712,
    0.9071260877501994,
    0.8973545375015536,
    0.8876882462632606,
    0.8781260801866497,
    0.8686669176368531,
    0.859309649061239,
    0.8500531768592617,
    0.8408964152537145,
    0.8318382901633682,
    0.8228777390769825,
    0.8140137109286739,
    0.8052451659746271,
    0.7965710756711335,
    0.7879904225539432,
    0.7795022001189185,
    0.7711054127039704,
    0.7627990753722692,
    0.7545822137967114,
    0.7464538641456324,
    0.7384130729697497,
    0.7304588970903235,
    0.7225904034885233,
    0.714806669195985,
    0.7071067811865476,
    0.6994898362691556,
    0.691954940981916,
    0.6845012114872953,
    0.6771277734684463,
    0.6698337620266515,
    0.6626183215798707,
    0.6554806057623822,
    0.6484197773255048,
    0.6414350080393891,
    0.6345254785958666,
    0.6276903785123455,
    0.620928906036742,
    0.614240268053435,
    0.6076236799902345,
    0.6010783657263515,
    0.5946035575013605,
    0.5881984958251406,
    0.5818624293887887,
    0.5755946149764913,
    0.5693943173783458,
    0.5632608093041209,
    0.5571933712979462,
    0.5511912916539204,
    0.5452538663326288,
    0.5393803988785599,
    0.5335702003384118,
    0.5278225891802786,
    0.5221368912137069,
    0.5165124395106142,
    0.5109485743270583,
    0.5054446430258502,
];

/// The median absolute deviation of Gaussian values times this is their
/// standard deviation.
pub const MAD_TO_SIGMA: f64 = 1.4826;

/// The median of `|v|` (0 for none; the upper middle of an even count);
/// reorders `v`.
pub fn median_abs(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    for x in v.iter_mut() {
        *x = x.abs();
    }
    let mid = v.len() / 2;
    v.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
    v[mid]
}

/// Square root, the same on every target.
#[inline]
pub fn sqrt(x: f64) -> f64 {
    libm::sqrt(x)
}

/// Largest integer not greater than `x`.
#[inline]
pub fn floor(x: f64) -> f64 {
    libm::floor(x)
}

/// Euclidean norm of a vector, through [`sqrt`].
#[inline]
pub fn norm(v: &Vec3) -> f64 {
    sqrt(v.norm_squared())
}

/// `true` when all three coordinates are finite.
#[inline]
pub fn is_finite(v: &Vec3) -> bool {
    v.x.is_finite() && v.y.is_finite() && v.z.is_finite()
}

/// Where the segment `a`-`b` comes nearest `p`: the parameter `t` in
/// `[0, 1]` of the point `a + t (b - a)` (0 for a segment of no length).
pub fn nearest_on_segment<const D: usize>(
    p: &nalgebra::SVector<f64, D>,
    a: &nalgebra::SVector<f64, D>,
    b: &nalgebra::SVector<f64, D>,
) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    if len2 > 0.0 {
        ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// Whether a node lies within a reach of a point, the node found last
/// tried first: the cloud's points come in runs along the rope, so most
/// are settled by one distance instead of one per node.
pub(crate) struct NearNodes<'a> {
    nodes: &'a [Vec3],
    reach_squared: f64,
    last: usize,
}

impl<'a> NearNodes<'a> {
    pub(crate) fn new(nodes: &'a [Vec3], reach: f64) -> Self {
        Self {
            nodes,
            reach_squared: reach * reach,
            last: 0,
        }
    }

    /// `true` when a node `k` that `counts(k)` lies within the reach of `p`.
    pub(crate) fn any(&mut self, p: &Vec3, counts: impl Fn(usize) -> bool) -> bool {
        let within =
            |k: usize| counts(k) && (p - self.nodes[k]).norm_squared() <= self.reach_squared;
        if self.last < self.nodes.len() && within(self.last) {
            return true;
        }
        match (0..self.nodes.len()).find(|&k| within(k)) {
            Some(k) => {
                self.last = k;
                true
            }
            None => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_neg_matches_libm() {
        let mut worst: f64 = 0.0;
        for i in 0..200_000 {
            let x = i as f64 * 0.00035;
            let a = exp_neg(x);
            let b = libm::exp(-x);
            worst = worst.max(((a - b) / b).abs());
        }
        assert!(worst < 1e-13, "worst relative error {worst}");
        assert_eq!(exp_neg(0.0), 1.0);
        assert_eq!(exp_neg(-1.0), libm::exp(1.0));
        assert!(exp_neg(f64::NAN).is_nan());
    }
}
