//! 2D smoothing kernels for SPH: values, radial derivatives and Laplacians. Pure maths, no ECS.
//!
//! Every kernel here is written in terms of its *support radius* `H` (the kernel is zero for
//! `r >= H`) and normalised for two dimensions, so that its integral over the plane is one. The
//! unit tests at the bottom integrate each kernel numerically and compare the closed-form
//! derivative and Laplacian against finite differences, because published 2D constants disagree
//! with each other (a 2D spiky gradient quoted as `-10/(πH⁵)` is off by a factor of three, and the
//! `40/(πH⁵)(H-r)` often quoted as the 2D viscosity Laplacian is not the Laplacian of the 2D
//! viscosity kernel at all).
//!

use bevy::math::Vec4;
use bevy::reflect::Reflect;
use core::f32::consts::PI;

/// Which kernels the solver uses for density (`W`) and for the pressure and viscosity gradients
/// (`∇W`).
#[derive(Reflect, Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum KernelKind {
    /// [`WendlandC2`] for both: smooth and free of pairing instability.
    #[default]
    WendlandC2,
    /// [`CubicSpline`] for both: the classic SPH kernel.
    CubicSpline,
    /// Müller et al. (2003): [`Poly6`] for density, [`Spiky`] for gradients.
    Muller,
}

impl KernelKind {
    /// Every choice, for menus.
    pub const ALL: [KernelKind; 3] = [Self::WendlandC2, Self::CubicSpline, Self::Muller];

    /// A short human-readable name.
    pub fn label(self) -> &'static str {
        match self {
            Self::WendlandC2 => "Wendland C2",
            Self::CubicSpline => "cubic spline",
            Self::Muller => "Müller poly6/spiky",
        }
    }
}

/// A radially symmetric 2D kernel `W(r)` with compact support.
pub trait RadialKernel: Copy + Send + Sync + 'static {
    /// Support radius `H`, m: `W(r) = 0` for `r >= H`.
    fn support(&self) -> f32;
    /// `W(r)`, 1/m².
    fn value(&self, r: f32) -> f32;
    /// `W` from the squared distance; kernels that are polynomials in `r²` skip the square root.
    #[inline]
    fn value_sq(&self, r2: f32) -> f32 {
        self.value(r2.sqrt())
    }
    /// Radial derivative `dW/dr`, 1/m³.
    fn derivative(&self, r: f32) -> f32;
    /// `(dW/dr) / r`, 1/m⁴: the gradient is this times the separation vector. Finite at `r = 0`
    /// for kernels whose slope vanishes there; callers skip `r = 0` for the others.
    #[inline]
    fn derivative_over_r(&self, r: f32) -> f32 {
        self.derivative(r) / r
    }
    /// 2D Laplacian `∇²W = W'' + W'/r`, 1/m⁴.
    fn laplacian(&self, r: f32) -> f32;
    /// [`value_sq`](Self::value_sq) on four lanes at once; zero beyond the support (also for
    /// `r² = ∞`).
    fn value_sq_x4(&self, r2: Vec4) -> Vec4;
    /// [`value_sq_x4`](Self::value_sq_x4) given the distances `r = √r²` as well, bit for bit
    /// the same: a pass that needs `r` for the gradient takes one square root, not two.
    #[inline]
    fn value_x4(&self, r: Vec4, r2: Vec4) -> Vec4 {
        let _ = r;
        self.value_sq_x4(r2)
    }
    /// [`derivative_over_r`](Self::derivative_over_r) on four lanes at once (`r > 0`).
    fn derivative_over_r_x4(&self, r: Vec4) -> Vec4;
    /// The slope over `r` that pressure and viscosity push with: [`derivative_over_r`](Self::derivative_over_r)
    /// beyond the distance where `|dW/dr|` peaks, and that peak's `|dW/dr|` held closer in
    /// (Thomas & Couchman 1992). A kernel whose slope vanishes at `r = 0` otherwise pushes two
    /// particles apart less the closer they come, so that compressed particles pair up and sit at
    /// one point (the pairing instability). Kernels whose slope peaks at `r = 0` keep theirs.
    #[inline]
    fn push_slope(&self, r: f32) -> f32 {
        self.derivative_over_r(r)
    }
    /// [`push_slope`](Self::push_slope) on four lanes at once (`r > 0`).
    #[inline]
    fn push_slope_x4(&self, r: Vec4) -> Vec4 {
        self.derivative_over_r_x4(r)
    }
}

/// Müller et al. (2003) poly6 kernel, 2D: `W = 4/(πH⁸) (H² − r²)³`. Used for density.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Poly6 {
    support: f32,
    support_sq: f32,
    norm: f32,
}

impl Poly6 {
    /// The kernel with support radius `support` (m).
    pub fn new(support: f32) -> Self {
        Self {
            support,
            support_sq: support * support,
            norm: 4.0 / (PI * support.powi(8)),
        }
    }
}

impl RadialKernel for Poly6 {
    fn support(&self) -> f32 {
        self.support
    }
    #[inline]
    fn value(&self, r: f32) -> f32 {
        self.value_sq(r * r)
    }
    #[inline]
    fn value_sq(&self, r2: f32) -> f32 {
        // Clamped rather than branched: zero beyond the support without a misprediction.
        let d = (self.support_sq - r2).max(0.0);
        self.norm * d * d * d
    }
    #[inline]
    fn derivative(&self, r: f32) -> f32 {
        r * self.derivative_over_r(r)
    }
    #[inline]
    fn derivative_over_r(&self, r: f32) -> f32 {
        let d = (self.support_sq - r * r).max(0.0);
        -6.0 * self.norm * d * d
    }
    fn laplacian(&self, r: f32) -> f32 {
        let r2 = r * r;
        if r2 >= self.support_sq {
            return 0.0;
        }
        let d = self.support_sq - r2;
        // W' = -6 N r d², W'' = -6 N d² + 24 N r² d; W'' + W'/r = N d (24 r² − 12 d).
        self.norm * d * (24.0 * r2 - 12.0 * d)
    }
    #[inline]
    fn value_sq_x4(&self, r2: Vec4) -> Vec4 {
        let d = (Vec4::splat(self.support_sq) - r2).max(Vec4::ZERO);
        self.norm * d * d * d
    }
    #[inline]
    fn derivative_over_r_x4(&self, r: Vec4) -> Vec4 {
        let d = (Vec4::splat(self.support_sq) - r * r).max(Vec4::ZERO);
        -6.0 * self.norm * d * d
    }
}

/// Müller et al. (2003) spiky kernel, 2D: `W = 10/(πH⁵) (H − r)³`. Its gradient does not vanish
/// at `r = 0`, so close particles still push each other apart; used for pressure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spiky {
    support: f32,
    norm: f32,
}

impl Spiky {
    /// The kernel with support radius `support` (m).
    pub fn new(support: f32) -> Self {
        Self {
            support,
            norm: 10.0 / (PI * support.powi(5)),
        }
    }
}

impl RadialKernel for Spiky {
    fn support(&self) -> f32 {
        self.support
    }
    #[inline]
    fn value(&self, r: f32) -> f32 {
        let d = (self.support - r).max(0.0);
        self.norm * d * d * d
    }
    #[inline]
    fn derivative(&self, r: f32) -> f32 {
        let d = (self.support - r).max(0.0);
        -3.0 * self.norm * d * d
    }
    fn laplacian(&self, r: f32) -> f32 {
        if r >= self.support {
            return 0.0;
        }
        let d = self.support - r;
        // W'' = 6 N d, W'/r = -3 N d² / r.
        self.norm * (6.0 * d - 3.0 * d * d / r)
    }
    #[inline]
    fn value_sq_x4(&self, r2: Vec4) -> Vec4 {
        self.value_x4(r2.sqrt(), r2)
    }
    #[inline]
    fn value_x4(&self, r: Vec4, _r2: Vec4) -> Vec4 {
        let d = (Vec4::splat(self.support) - r).max(Vec4::ZERO);
        self.norm * d * d * d
    }
    #[inline]
    fn derivative_over_r_x4(&self, r: Vec4) -> Vec4 {
        let d = (Vec4::splat(self.support) - r).max(Vec4::ZERO);
        -3.0 * self.norm * d * d / r
    }
}

/// Müller et al. (2003) viscosity kernel, normalised for 2D:
/// `W = 10/(3πH²) (−r³/(2H³) + r²/H² + H/(2r) − 1)`.
///
/// Its true 2D Laplacian is `10/(3πH²) (4/H² − 9r/(2H³) + H/(2r³))`, which is singular at
/// `r = 0` (the linear `(H − r)` form belongs to the 3D kernel). The solver therefore computes
/// viscosity with the gradient-based Morris/Lo–Shao operator for every kernel choice; this kernel
/// is here, tested, for users who want Müller's formulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Viscosity {
    support: f32,
    norm: f32,
}

impl Viscosity {
    /// The kernel with support radius `support` (m).
    pub fn new(support: f32) -> Self {
        Self {
            support,
            norm: 10.0 / (3.0 * PI * support * support),
        }
    }
}

impl RadialKernel for Viscosity {
    fn support(&self) -> f32 {
        self.support
    }
    fn value(&self, r: f32) -> f32 {
        let h = self.support;
        if r >= h || r <= 0.0 {
            return if r <= 0.0 { f32::INFINITY } else { 0.0 };
        }
        self.norm * (-r * r * r / (2.0 * h * h * h) + r * r / (h * h) + h / (2.0 * r) - 1.0)
    }
    fn derivative(&self, r: f32) -> f32 {
        let h = self.support;
        if r >= h {
            return 0.0;
        }
        self.norm * (-1.5 * r * r / (h * h * h) + 2.0 * r / (h * h) - h / (2.0 * r * r))
    }
    fn laplacian(&self, r: f32) -> f32 {
        let h = self.support;
        if r >= h {
            return 0.0;
        }
        self.norm * (4.0 / (h * h) - 4.5 * r / (h * h * h) + h / (2.0 * r * r * r))
    }
    fn value_sq_x4(&self, r2: Vec4) -> Vec4 {
        Vec4::from_array(r2.to_array().map(|r2| self.value_sq(r2)))
    }
    fn derivative_over_r_x4(&self, r: Vec4) -> Vec4 {
        Vec4::from_array(r.to_array().map(|r| self.derivative_over_r(r)))
    }
}

/// Wendland C2 kernel, 2D: `W = 7/(πH²) (1 − q)⁴ (1 + 4q)` with `q = r/H`. Smooth, positive
/// Fourier transform (no pairing instability); the default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WendlandC2 {
    support: f32,
    inv_support: f32,
    norm: f32,
    peak: Peak,
}

impl WendlandC2 {
    /// The kernel with support radius `support` (m).
    pub fn new(support: f32) -> Self {
        let kernel = Self {
            support,
            inv_support: 1.0 / support,
            norm: 7.0 / (PI * support * support),
            peak: Peak::default(),
        };
        Self {
            peak: Peak::of(&kernel, 0.25 * support),
            ..kernel
        }
    }
}

impl RadialKernel for WendlandC2 {
    fn support(&self) -> f32 {
        self.support
    }
    #[inline]
    fn value(&self, r: f32) -> f32 {
        let q = (r * self.inv_support).min(1.0);
        let t = 1.0 - q;
        let t2 = t * t;
        self.norm * t2 * t2 * (1.0 + 4.0 * q)
    }
    #[inline]
    fn derivative(&self, r: f32) -> f32 {
        r * self.derivative_over_r(r)
    }
    #[inline]
    fn derivative_over_r(&self, r: f32) -> f32 {
        let t = (1.0 - r * self.inv_support).max(0.0);
        // dW/dq = -20 N q (1-q)³, dq/dr = 1/H, so W'/r = -20 N (1-q)³ / H².
        -20.0 * self.norm * t * t * t * self.inv_support * self.inv_support
    }
    fn laplacian(&self, r: f32) -> f32 {
        let q = r * self.inv_support;
        if q >= 1.0 {
            return 0.0;
        }
        let t = 1.0 - q;
        let c = self.norm * self.inv_support * self.inv_support;
        // W'' = -20 c (1-q)²(1-4q), W'/r = -20 c (1-q)³.
        -20.0 * c * t * t * ((1.0 - 4.0 * q) + t)
    }
    #[inline]
    fn value_sq_x4(&self, r2: Vec4) -> Vec4 {
        self.value_x4(r2.sqrt(), r2)
    }
    #[inline]
    fn value_x4(&self, r: Vec4, _r2: Vec4) -> Vec4 {
        let q = (r * self.inv_support).min(Vec4::ONE);
        let t = Vec4::ONE - q;
        let t2 = t * t;
        self.norm * t2 * t2 * (Vec4::ONE + 4.0 * q)
    }
    #[inline]
    fn derivative_over_r_x4(&self, r: Vec4) -> Vec4 {
        let t = (Vec4::ONE - r * self.inv_support).max(Vec4::ZERO);
        (-20.0 * self.norm * self.inv_support * self.inv_support) * t * t * t
    }
    #[inline]
    fn push_slope(&self, r: f32) -> f32 {
        self.peak.hold(r, self.derivative_over_r(r))
    }
    #[inline]
    fn push_slope_x4(&self, r: Vec4) -> Vec4 {
        self.peak.hold_x4(r, self.derivative_over_r_x4(r))
    }
}

/// Cubic B-spline kernel (Monaghan & Lattanzio 1985), 2D, written with support radius `H = 2h`:
/// `W = 10/(7πh²) (1 − 3/2 s² + 3/4 s³)` for `s = r/h < 1`, `10/(7πh²) (2 − s)³/4` for `s < 2`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CubicSpline {
    support: f32,
    inv_h: f32,
    norm: f32,
    peak: Peak,
}

impl CubicSpline {
    /// The kernel with support radius `support` (m); its smoothing length is half of it.
    pub fn new(support: f32) -> Self {
        let h = 0.5 * support;
        let kernel = Self {
            support,
            inv_h: 1.0 / h,
            norm: 10.0 / (7.0 * PI * h * h),
            peak: Peak::default(),
        };
        Self {
            peak: Peak::of(&kernel, support / 3.0),
            ..kernel
        }
    }
}

impl RadialKernel for CubicSpline {
    fn support(&self) -> f32 {
        self.support
    }
    #[inline]
    fn value(&self, r: f32) -> f32 {
        // (2 − s)³/4 − (1 − s)³ with both terms clamped at zero is the spline on every piece.
        let s = r * self.inv_h;
        let outer = (2.0 - s).max(0.0);
        let inner = (1.0 - s).max(0.0);
        self.norm * (0.25 * outer * outer * outer - inner * inner * inner)
    }
    #[inline]
    fn derivative(&self, r: f32) -> f32 {
        let s = r * self.inv_h;
        if s >= 2.0 {
            0.0
        } else if s >= 1.0 {
            let t = 2.0 - s;
            -0.75 * self.norm * t * t * self.inv_h
        } else {
            self.norm * (-3.0 * s + 2.25 * s * s) * self.inv_h
        }
    }
    #[inline]
    fn derivative_over_r(&self, r: f32) -> f32 {
        // Both pieces computed and one selected, so lanes vectorise without branches.
        let s = r * self.inv_h;
        let c = self.norm * self.inv_h * self.inv_h;
        let outer = (2.0 - s).max(0.0);
        let far = -0.75 * c * outer * outer / s.max(1.0);
        let near = c * (-3.0 + 2.25 * s);
        if s < 1.0 { near } else { far }
    }
    fn laplacian(&self, r: f32) -> f32 {
        let s = r * self.inv_h;
        let c = self.norm * self.inv_h * self.inv_h;
        if s >= 2.0 {
            0.0
        } else if s >= 1.0 {
            let t = 2.0 - s;
            // W'' = 1.5 c t, W'/r = -0.75 c t² / s.
            c * (1.5 * t - 0.75 * t * t / s)
        } else {
            // W'' = c(-3 + 4.5 s), W'/r = c(-3 + 2.25 s).
            c * (-6.0 + 6.75 * s)
        }
    }
    #[inline]
    fn value_sq_x4(&self, r2: Vec4) -> Vec4 {
        self.value_x4(r2.sqrt(), r2)
    }
    #[inline]
    fn value_x4(&self, r: Vec4, _r2: Vec4) -> Vec4 {
        let s = r * self.inv_h;
        let outer = (Vec4::splat(2.0) - s).max(Vec4::ZERO);
        let inner = (Vec4::ONE - s).max(Vec4::ZERO);
        self.norm * (0.25 * outer * outer * outer - inner * inner * inner)
    }
    #[inline]
    fn derivative_over_r_x4(&self, r: Vec4) -> Vec4 {
        let s = r * self.inv_h;
        let c = self.norm * self.inv_h * self.inv_h;
        let outer = (Vec4::splat(2.0) - s).max(Vec4::ZERO);
        let far = -0.75 * c * outer * outer / s.max(Vec4::ONE);
        let near = c * (Vec4::splat(-3.0) + 2.25 * s);
        Vec4::select(s.cmplt(Vec4::ONE), near, far)
    }
    #[inline]
    fn push_slope(&self, r: f32) -> f32 {
        self.peak.hold(r, self.derivative_over_r(r))
    }
    #[inline]
    fn push_slope_x4(&self, r: Vec4) -> Vec4 {
        self.peak.hold_x4(r, self.derivative_over_r_x4(r))
    }
}

/// Where a kernel's `|dW/dr|` peaks, m, and `dW/dr` there, 1/m³: what
/// [`RadialKernel::push_slope`] holds inside the peak.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Peak {
    at: f32,
    slope: f32,
}

impl Peak {
    /// The peak of `kernel` at `at`.
    fn of<K: RadialKernel>(kernel: &K, at: f32) -> Self {
        Self {
            at,
            slope: kernel.derivative(at),
        }
    }

    /// The push slope over `r` at `r`, given the kernel's own `dW/dr / r` there (`slope`).
    #[inline]
    fn hold(self, r: f32, slope: f32) -> f32 {
        if r < self.at { self.slope / r } else { slope }
    }

    /// [`hold`](Self::hold) on four lanes at once.
    #[inline]
    fn hold_x4(self, r: Vec4, slope: Vec4) -> Vec4 {
        let held = Vec4::splat(self.slope) / r;
        Vec4::select(r.cmplt(Vec4::splat(self.at)), held, slope)
    }
}

/// Sum of `W(|(i, j)| · spacing)` over an infinite square lattice of the given spacing: the
/// density an interior particle of that lattice has per unit particle mass, 1/m².
pub fn lattice_sum<K: RadialKernel>(kernel: &K, spacing: f32) -> f64 {
    let reach = (kernel.support() / spacing).ceil() as i32 + 1;
    let mut sum = 0.0f64;
    for j in -reach..=reach {
        for i in -reach..=reach {
            let r2 = ((i * i + j * j) as f32) * spacing * spacing;
            sum += kernel.value_sq(r2) as f64;
        }
    }
    sum
}

/// `Σⱼ (xⱼ − xᵢ)ₓ ∂ₓW(xᵢ − xⱼ)` over an infinite square lattice of the given spacing, the
/// particle `i` at a lattice point: the first moment of the gradient, which the continuous kernel
/// makes one per unit volume. Dimensionless times 1/m², like [`lattice_sum`]; their ratio is the
/// gradient's consistency on the lattice.
pub fn lattice_gradient_moment<K: RadialKernel>(kernel: &K, spacing: f32) -> f64 {
    let reach = (kernel.support() / spacing).ceil() as i32 + 1;
    let mut sum = 0.0f64;
    for j in -reach..=reach {
        for i in -reach..=reach {
            if i == 0 && j == 0 {
                continue;
            }
            let x = (i as f64) * spacing as f64;
            let r = ((i * i + j * j) as f64).sqrt() * spacing as f64;
            // ∇ᵢW(xᵢ − xⱼ) = W'(r) (xᵢ − xⱼ)/r with xᵢ − xⱼ = −x.
            let gradient_x = kernel.derivative(r as f32) as f64 * (-x) / r;
            sum += x * gradient_x;
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    const H: f32 = 0.37;

    /// `∫ W d²x` over the disc of radius `H`, by the midpoint rule in `r` (f64 accumulation).
    fn integral<K: RadialKernel>(k: &K, from: f64) -> f64 {
        let n = 200_000;
        let h = k.support() as f64;
        let dr = (h - from) / n as f64;
        (0..n)
            .map(|i| {
                let r = from + (i as f64 + 0.5) * dr;
                2.0 * core::f64::consts::PI * r * k.value(r as f32) as f64 * dr
            })
            .sum()
    }

    /// Relative-or-absolute error of `got` against `want`, scaled by `scale`.
    fn close(got: f64, want: f64, scale: f64, tol: f64) -> bool {
        (got - want).abs() <= tol * scale.max(want.abs())
    }

    fn check_kernel<K: RadialKernel>(name: &str, k: K, r_min: f32) {
        // Normalisation: the integral over the plane is one.
        let total = integral(&k, 0.0);
        assert!((total - 1.0).abs() < 2e-4, "{name}: ∫W = {total}, want 1");

        // Compact support.
        assert_eq!(k.value(H), 0.0, "{name}: W(H) must vanish");
        assert_eq!(k.value(1.5 * H), 0.0, "{name}: W beyond H must vanish");
        assert_eq!(
            k.derivative(1.2 * H),
            0.0,
            "{name}: W' beyond H must vanish"
        );

        // Derivative and Laplacian against central finite differences (in f64 on f32 values, so
        // the step must not be too small).
        let eps = 1e-3 * H;
        let scale = k.value(r_min.max(0.05 * H)).abs() as f64 / (H as f64);
        for i in 1..40 {
            let r = r_min + (H - r_min) * i as f32 / 40.0;
            if (r - H).abs() < 2.0 * eps {
                continue;
            }
            let w = |x: f32| k.value(x) as f64;
            let d_num = (w(r + eps) - w(r - eps)) / (2.0 * eps as f64);
            let d = k.derivative(r) as f64;
            assert!(
                close(d, d_num, scale, 2e-3),
                "{name}: W'({r}) = {d}, finite difference {d_num}"
            );
            let d_over_r = k.derivative_over_r(r) as f64;
            assert!(
                close(d_over_r * r as f64, d, scale, 1e-5),
                "{name}: W'/r inconsistent at r = {r}"
            );
            // W'' from differences of the (just verified) W': a second difference of f32 values
            // would drown in rounding.
            let dw = |x: f32| k.derivative(x) as f64;
            let d2_num = (dw(r + eps) - dw(r - eps)) / (2.0 * eps as f64);
            let lap_num = d2_num + d / r as f64;
            let lap = k.laplacian(r) as f64;
            assert!(
                close(lap, lap_num, scale / H as f64, 2e-2),
                "{name}: ∇²W({r}) = {lap}, finite difference {lap_num}"
            );
        }
    }

    #[test]
    fn poly6_is_normalised_with_matching_derivatives() {
        check_kernel("poly6", Poly6::new(H), 0.02 * H);
    }

    #[test]
    fn spiky_is_normalised_with_matching_derivatives() {
        check_kernel("spiky", Spiky::new(H), 0.05 * H);
        // The gradient constant: |W'(0)| = 30/(πH⁵) · H² = 30/(πH³).
        let w0 = Spiky::new(H).derivative(0.0) as f64;
        let want = -30.0 / (core::f64::consts::PI * (H as f64).powi(3));
        assert!((w0 - want).abs() < 1e-4 * want.abs());
    }

    #[test]
    fn viscosity_is_normalised_with_matching_derivatives() {
        check_kernel("viscosity", Viscosity::new(H), 0.1 * H);
        // The 3D-shaped "40/(πH⁵)(H − r)" is not its 2D Laplacian.
        let k = Viscosity::new(H);
        for r in [0.2 * H, 0.8 * H] {
            let folklore = 40.0 / (PI * H.powi(5)) * (H - r);
            assert!((k.laplacian(r) - folklore).abs() > 0.3 * folklore);
        }
    }

    #[test]
    fn wendland_c2_is_normalised_with_matching_derivatives() {
        check_kernel("wendland C2", WendlandC2::new(H), 0.01 * H);
        assert!(WendlandC2::new(H).derivative_over_r(0.0).is_finite());
    }

    #[test]
    fn cubic_spline_is_normalised_with_matching_derivatives() {
        check_kernel("cubic spline", CubicSpline::new(H), 0.01 * H);
    }

    fn check_lanes<K: RadialKernel>(name: &str, k: K) {
        for i in 0..50 {
            let r = [0.013, 0.37, 0.61, 0.999, 1.0, 1.4].map(|f| f * H * (1.0 + i as f32 * 1e-3));
            for chunk in r.chunks(2) {
                let lanes = Vec4::new(chunk[0], chunk[1], chunk[0] * 0.5, chunk[1] * 0.25);
                let values = k.value_sq_x4(lanes * lanes).to_array();
                let slopes = k.derivative_over_r_x4(lanes).to_array();
                let pushes = k.push_slope_x4(lanes).to_array();
                for (lane, &r) in lanes.to_array().iter().enumerate() {
                    let want = k.push_slope(r);
                    assert!(
                        (pushes[lane] - want).abs() <= 1e-4 * want.abs().max(1.0),
                        "{name}: push slope({r})"
                    );
                    let want = k.value_sq(r * r);
                    assert!(
                        (values[lane] - want).abs() <= 1e-5 * want.abs().max(1.0),
                        "{name}: W({r})"
                    );
                    let want = k.derivative_over_r(r);
                    assert!(
                        (slopes[lane] - want).abs() <= 1e-4 * want.abs().max(1.0),
                        "{name}: W'/r({r})"
                    );
                }
            }
        }
        assert_eq!(
            k.value_sq_x4(Vec4::splat(f32::INFINITY)),
            Vec4::ZERO,
            "{name}: W(∞)"
        );
    }

    #[test]
    fn the_push_holds_the_peak_slope_inside_it() {
        fn check<K: RadialKernel>(name: &str, k: K, peak: f32) {
            let held = k.derivative(peak);
            assert!(
                (k.derivative(peak * 0.99) - held) >= 0.0
                    && (k.derivative(peak * 1.01) - held) >= 0.0,
                "{name}: |W'| peaks at {peak}"
            );
            for f in [1e-4, 0.01, 0.3, 0.7, 0.999] {
                let r = f * peak;
                let push = k.push_slope(r) * r;
                assert!(
                    (push - held).abs() <= 1e-5 * held.abs(),
                    "{name}: push at {r}"
                );
                assert!(
                    push <= k.derivative(r),
                    "{name}: push weaker than W' at {r}"
                );
            }
            for f in [1.0, 1.01, 1.5, 3.0] {
                let r = (f * peak).min(H);
                assert_eq!(k.push_slope(r), k.derivative_over_r(r), "{name}: at {r}");
            }
        }
        check("wendland", WendlandC2::new(H), 0.25 * H);
        check("cubic", CubicSpline::new(H), H / 3.0);
        let spiky = Spiky::new(H);
        assert_eq!(
            spiky.push_slope(0.01 * H),
            spiky.derivative_over_r(0.01 * H)
        );
    }

    #[test]
    fn lane_versions_match_scalar_versions() {
        check_lanes("poly6", Poly6::new(H));
        check_lanes("spiky", Spiky::new(H));
        check_lanes("wendland", WendlandC2::new(H));
        check_lanes("cubic", CubicSpline::new(H));
    }

    #[test]
    fn second_moment_gives_the_laplacian_scale() {
        // ∫ r² ∇²W d²x = 4 ∫ W d²x = 4 for smooth kernels: the Laplacian operator built on these
        // kernels has the right magnitude.
        type Laplacian = Box<dyn Fn(f32) -> f32>;
        let cases: [(&str, Laplacian); 3] = [
            ("wendland", Box::new(|r| WendlandC2::new(H).laplacian(r))),
            ("cubic", Box::new(|r| CubicSpline::new(H).laplacian(r))),
            ("poly6", Box::new(|r| Poly6::new(H).laplacian(r))),
        ];
        for (name, lap) in cases {
            let n = 100_000;
            let dr = H as f64 / n as f64;
            let m: f64 = (0..n)
                .map(|i| {
                    let r = (i as f64 + 0.5) * dr;
                    2.0 * core::f64::consts::PI * r * r * r * lap(r as f32) as f64 * dr
                })
                .sum();
            assert!((m - 4.0).abs() < 1e-3, "{name}: ∫r²∇²W = {m}");
        }
    }

    #[test]
    fn lattice_sum_approaches_one_over_cell_area() {
        // With many neighbours the lattice sum tends to the integral, 1/spacing².
        for support in [4.0, 8.0] {
            let s = lattice_sum(&WendlandC2::new(support), 1.0);
            assert!((s - 1.0).abs() < 2e-3, "support {support}: lattice sum {s}");
        }
    }
}
