//! Surface tension in N/m, as a surface stress (Lafaurie et al. 1994; the continuum surface
//! force of Brackbill, Kothe & Zemach 1992 written as the divergence of a stress): a
//! non-pressure pass that every pressure solver gets ([`FluidStep`](super::step::FluidStep)
//! runs it after the solver's forces). Experimental: see "Surface tension" in
//! `docs/physics.md` for what it meets and what it does not yet.
//!
//! A surface pulls along itself with `σ` per metre: the stress `T = σ δₛ (I − n̂ n̂)`, `n̂` its
//! normal and `δₛ` a delta function across it, whose divergence is the familiar `σ κ δₛ n̂`
//! on a curved surface (a drop's Laplace jump `σ/R`) and nothing on a flat one. With no
//! particles outside the liquid, the colour function `c = Σⱼ Vⱼ Wᵢⱼ` (walls counted as liquid)
//! falls from one to nothing across the surface, and its gradient `nᵢ = Σⱼ Vⱼ ∇ᵢWᵢⱼ` is
//! `δₛ n̂` but for the part of the fall beyond the last particles. That part is taken from the
//! rest lattice ([`calibrate`]): on a flat surface of it the particles of a column carry
//! `S = Σₖ V |nₖ| / Δx` of the delta's unit integral (0.47 at two spacings' support).
//!
//! The stress is summed pair by pair, `aᵢ = (σ / S ρ₀) Σⱼ Vⱼ (Tᵢ + Tⱼ) · ∇ᵢWᵢⱼ`, so the pulls
//! are equal and opposite and a drop keeps its momentum. Three things hold it together at a
//! resolution of a particle:
//! - particles whose colour gradient is under [`SURFACE_FRACTION`] of a flat surface's are
//!   inside the liquid and carry no stress (their gradient is noise);
//! - a tension pulls neighbours the harder the closer they come where a kernel's slope steepens
//!   inward, so they pair up and the pairs fly off (measured: the closest pair in a drop at
//!   0.3 spacings after 0.06 s); each pair's pull is held at close range ([`hold`], Monaghan's
//!   2000 artificial stress on the surface stress alone);
//! - the tangential stress alone pushes a particle lifted out of a flat surface further out
//!   (measured: +4.75 m/s² at 0.3 spacings): the stress carries as much again isotropically
//!   ([`ISOTROPIC`]), which the pressure takes up inside the liquid, so the surface tension is
//!   unchanged, and which pulls a lifted particle back.
//!
//! Walls wet by their contact angle θ (Young: the wetted wall pulls the contact line out with
//! `σ cos θ`): the liquid along a wall carries a second stress, `−σ cos θ δ_w (I − n̂_w n̂_w)`,
//! its delta the walls' part of the colour gradient. It is uniform along a wetted wall and
//! acts where the wetted area ends, moving the contact line until the free surface meets the
//! wall at θ. Across the wall the same liquid is pulled to it ([`ADHESION`]), so that what
//! wets a ceiling hangs from it.
//!
//! The pull is stable for steps under the capillary limit [`capillary_time_step`].

use super::config::{SphConstants, SurfaceCalibration};
use super::density::with_kernels;
use super::kernels::RadialKernel;
use super::layout::{FluidSnapshot, LANES, Walls};
use super::parallel::{Parallel, for_each_slot};
use bevy::math::{Vec2, Vec4};

/// A particle is on the surface (it carries the stress) where its colour gradient is at least
/// this fraction of a flat surface's top row; a jittered interior particle reads under 15% of
/// it.
pub const SURFACE_FRACTION: f32 = 0.25;

/// The isotropic part of the surface stress, a fraction of the tangential part (see the module
/// docs). Measured on a weightless 2:1 block of 1,257 particles: at 0.5 a particle left the
/// drop within a second; at 1 none did in 3 s.
pub const ISOTROPIC: f32 = 1.0;

/// The wetted wall's pull towards the wall, per unit `σ δ_w (1 + cos θ)`, which the wall
/// particles exert on the liquid next to them: it holds the liquid that wets a wall to it, and
/// leaves the contact angle as it is. Measured on a 3 mm drop touching the ceiling: it hangs
/// at 30° and falls at 150° (without the pull it falls at both); drops on a floor settle
/// within 9° of where they do without it.
pub const ADHESION: f32 = 0.08;

/// `ε` of [`hold`]: above 0.13 a pair's pull grows as it stretches from a spacing (Wendland C2,
/// two spacings' support).
pub const HOLD: f32 = 0.3;

/// The [`SurfaceCalibration`] of a square lattice of `spacing` (m) with particle volume
/// `volume` (m²), for the kernels `w` and `g` the pass takes values and gradients of.
pub fn calibrate<K: RadialKernel, G: RadialKernel>(
    w: &K,
    g: &G,
    spacing: f32,
    volume: f32,
) -> SurfaceCalibration {
    let reach = (g.support() / spacing).ceil() as i32 + 1;
    let dx = spacing as f64;
    let r = |i: i32, j: i32| ((i * i + j * j) as f64).sqrt() * dx;
    // Row k of the lattice's top rows, at y = −k Δx; the liquid fills y ≤ 0.
    let row = |k: i32| -> f64 {
        let mut sum = 0.0f64;
        for j in 0..=k + reach {
            for i in -reach..=reach {
                let (y, r) = ((j - k) as f64 * dx, r(i, j - k));
                if r > 0.0 {
                    // ∂ᵧWᵢⱼ = W'(r) (yᵢ − yⱼ)/r with yᵢ − yⱼ = y.
                    sum += g.derivative(r as f32) as f64 * y / r;
                }
            }
        }
        (sum * volume as f64).abs()
    };
    let top_row = row(0);
    let integral: f64 = (0..=reach)
        .map(row)
        .filter(|&n| n >= SURFACE_FRACTION as f64 * top_row)
        .map(|n| n * volume as f64 / dx)
        .sum();
    // The stress's first moment on the lattice with the held slope, against the kernel's.
    let reference = w.value(spacing);
    let (mut plain, mut held) = (0.0f64, 0.0f64);
    for j in -reach..=reach {
        for i in -reach..=reach {
            let r = r(i, j);
            if r > 0.0 {
                let x = i as f64 * dx;
                let moment = x * x * g.derivative(r as f32) as f64 / r;
                plain += moment;
                held += moment * hold(w.value(r as f32) / reference) as f64;
            }
        }
    }
    SurfaceCalibration {
        top_row: top_row as f32,
        integral: integral as f32,
        held: (plain / held) as f32,
    }
}

/// How much of a pair's surface stress acts at a kernel value `f = W(r)/W(Δx)`: `1 − ε f⁴`
/// with `ε =` [`HOLD`]: a pair pulls less as it closes from a spacing, and pushes apart under
/// about 0.7 of one.
#[inline]
fn hold(f: f32) -> f32 {
    let f2 = f * f;
    1.0 - HOLD * f2 * f2
}

/// The longest step (s) at which the shortest capillary waves a spacing `Δx` resolves stay
/// stable: `√(ρ₀ Δx³ / (2π σ))` (Brackbill et al. 1992); unlimited without tension.
pub fn capillary_time_step(c: &SphConstants) -> f32 {
    if c.surface_tension <= 0.0 {
        return f32::INFINITY;
    }
    let dx = c.spacing;
    (c.rest_density * dx * dx * dx / (core::f32::consts::TAU * c.surface_tension)).sqrt()
}

/// The pass's scratch, by sorted slot.
#[derive(Debug, Clone, Default)]
pub struct SurfaceTension {
    /// Each particle's surfaces: zero inside the liquid.
    surfaces: Vec<Surface>,
    /// Whether each carries a stress between liquid particles (not [`Surface::is_inside`]),
    /// padded with [`LANES`] nays: four neighbours' in one load.
    carries: Vec<bool>,
    /// The pull, m/s².
    acceleration: Vec<Vec2>,
}

impl SurfaceTension {
    /// The acceleration of surface tension (m/s², by sorted slot) for the positions of `fluid`
    /// and the `walls` (counted as liquid); `None` without tension.
    pub fn accelerations(
        &mut self,
        c: &SphConstants,
        fluid: &FluidSnapshot,
        walls: &Walls,
        parallel: &impl Parallel,
    ) -> Option<&[Vec2]> {
        if c.surface_tension <= 0.0 {
            return None;
        }
        let n = fluid.len();
        self.surfaces.resize(n, Surface::default());
        self.acceleration.resize(n, Vec2::ZERO);
        let threshold = SURFACE_FRACTION * c.surface.top_row;
        let pull =
            c.surface_tension * c.volume * c.surface.held / (c.surface.integral * c.rest_density);
        with_kernels!(c.kernel, c.support, |w, g| {
            for_each_slot(&mut self.surfaces, parallel, |slot, surface| {
                let colour = colour_gradient(&g, c, fluid.points.get(slot), fluid, walls);
                *surface = colour.surface(threshold);
                0.0
            });
            self.carries.clear();
            let carries = self.surfaces.iter().map(|s| !s.is_inside());
            self.carries.extend(carries.chain([false; LANES]));
            let surfaces = (&self.surfaces[..], &self.carries[..]);
            for_each_slot(&mut self.acceleration, parallel, |slot, a| {
                *a = pull * stress_divergence((&w, &g), c, slot, (fluid, walls), surfaces);
                0.0
            });
        });
        Some(&self.acceleration)
    }
}

/// The colour gradient at a point: the fluid's and the walls' parts, and the walls' wetting.
#[derive(Debug, Clone, Copy, Default)]
struct Colour {
    /// `Σⱼ V ∇ᵢWᵢⱼ` over the fluid, 1/m.
    fluid: Vec2,
    /// The same over the walls (counted as liquid), 1/m: towards the walls within reach.
    wall: Vec2,
    /// `cos θ` of the walls within reach, weighted by their gradients.
    wetting: f32,
}

impl Colour {
    /// The surfaces this colour gradient marks, each where its gradient reaches `threshold`
    /// (1/m): the free surface, whose normal is the whole gradient (the walls counted as
    /// liquid, so the liquid along a wall has none), and the wetted wall, whose normal is the
    /// walls' part.
    fn surface(&self, threshold: f32) -> Surface {
        let free = self.fluid + self.wall;
        let wetted = self.wall.length() >= threshold;
        Surface {
            normal: if free.length() >= threshold {
                free
            } else {
                Vec2::ZERO
            },
            wall: if wetted { self.wall } else { Vec2::ZERO },
            wetting: if wetted { self.wetting } else { 0.0 },
        }
    }
}

/// One particle's share of the surfaces: the free surface's stress and the wetted wall's.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Surface {
    /// The free surface's colour gradient (inward), 1/m; zero inside the liquid.
    normal: Vec2,
    /// The walls' colour gradient (towards them), 1/m, where the liquid wets a wall.
    wall: Vec2,
    /// `cos θ` of that wall's contact angle.
    wetting: f32,
}

impl Surface {
    /// Whether it carries no stress between liquid particles: no free surface, and no wall
    /// that it wets at other than 90° (at 90° the wetted wall's tension is nil; the walls'
    /// pull across, [`wall_stress`](Self::wall_stress), needs no liquid neighbour's).
    fn is_inside(&self) -> bool {
        self.normal == Vec2::ZERO && (self.wall == Vec2::ZERO || self.wetting == 0.0)
    }

    /// Whether it carries no stress with the walls either.
    fn is_dry(&self) -> bool {
        self.normal == Vec2::ZERO && self.wall == Vec2::ZERO
    }

    /// `T · v`, per unit `σ δₛ`: the free surface's [`stress`] and the wetted wall's, a
    /// tension `σ_sl − σ_sv = −σ cos θ` along the wall (Young: where the wall is wetted it
    /// pulls the contact line out as hard as `σ cos θ`, so the free surface meets the wall at
    /// θ).
    #[inline]
    fn stress(&self, v: Vec2) -> Vec2 {
        let mut t = stress(self.normal, v);
        let length = self.wall.length();
        if length > 0.0 {
            let along = v - self.wall * (self.wall.dot(v) / (length * length));
            t -= self.wetting * length * along;
        }
        t
    }

    /// With a wall particle: [`stress`](Self::stress) and a pull towards the wall,
    /// [`ADHESION`] `(1 + cos θ)` across it (the work of adhesion is `σ (1 + cos θ)`), which
    /// only the walls exert (between liquid particles it would be a tension across the wall
    /// band, which pairs them up and throws them off).
    #[inline]
    fn wall_stress(&self, v: Vec2) -> Vec2 {
        let length = self.wall.length();
        let across = if length > 0.0 {
            ADHESION * (1.0 + self.wetting) * self.wall * (self.wall.dot(v) / length)
        } else {
            Vec2::ZERO
        };
        self.stress(v) + across
    }
}

/// The [`Colour`] gradient at `x` over the fluid and the walls: the inward normal of the
/// surface, as long as a flat surface's top row reads [`SurfaceCalibration::top_row`].
fn colour_gradient<G: RadialKernel>(
    g: &G,
    c: &SphConstants,
    x: Vec2,
    fluid: &FluidSnapshot,
    walls: &Walls,
) -> Colour {
    let mut colour = Colour::default();
    fluid.points.for_each_batch(x, |_, dx, dy, r2| {
        // ∇ᵢWᵢⱼ = W'/r (xᵢ − xⱼ), and (dx, dy) = xⱼ − xᵢ.
        let slope = slopes(g, c, r2);
        colour.fluid -= Vec2::new((slope * dx).element_sum(), (slope * dy).element_sum());
    });
    let mut weight = 0.0;
    walls.points.for_each_batch(x, |first, dx, dy, r2| {
        let slope = slopes(g, c, r2);
        colour.wall -= Vec2::new((slope * dx).element_sum(), (slope * dy).element_sum());
        if !walls.own_wetting {
            return;
        }
        // |∇W| = |W'/r| r.
        let magnitudes = (-slope * r2.max(Vec4::ZERO).sqrt()).to_array();
        for (lane, &m) in magnitudes.iter().enumerate() {
            if m > 0.0 {
                let own = walls.wetting.get(first + lane).copied().unwrap_or(f32::NAN);
                colour.wetting += m * if own.is_nan() { c.wetting } else { own };
                weight += m;
            }
        }
    });
    colour.fluid *= c.volume;
    colour.wall *= c.volume;
    colour.wetting = if weight > 0.0 {
        colour.wetting / weight
    } else {
        c.wetting
    };
    colour
}

/// `W'(r)/r` on four lanes of squared distances `r2`: zero at `r = 0` and beyond the support.
#[inline]
fn slopes<G: RadialKernel>(g: &G, c: &SphConstants, r2: Vec4) -> Vec4 {
    let tiny = Vec4::splat(1e-12 * c.support_sq);
    let inside = r2.cmplt(Vec4::splat(c.support_sq)) & r2.cmpgt(tiny);
    Vec4::select(
        inside,
        g.derivative_over_r_x4(r2.max(tiny).sqrt()),
        Vec4::ZERO,
    )
}

/// `T · v` for the surface stress of the normal `n`, per unit `σ δₛ`:
/// `T = |n| ((1 + β) I − n̂ n̂)` with `β =` [`ISOTROPIC`].
#[inline]
fn stress(n: Vec2, v: Vec2) -> Vec2 {
    let length = n.length();
    if length > 0.0 {
        (1.0 + ISOTROPIC) * length * v - n * (n.dot(v) / length)
    } else {
        Vec2::ZERO
    }
}

/// `Σⱼ (Tᵢ + Tⱼ) · ∇ᵢWᵢⱼ hold(Wᵢⱼ/W(Δx))` over the neighbours of sorted `slot` (walls carry
/// no stress of their own), 1/m⁴ per unit `σ δₛ`: the divergence of the stress, pair by pair
/// opposite.
fn stress_divergence<K: RadialKernel, G: RadialKernel>(
    (w, g): (&K, &G),
    c: &SphConstants,
    slot: usize,
    (fluid, walls): (&FluidSnapshot, &Walls),
    (surfaces, carries): (&[Surface], &[bool]),
) -> Vec2 {
    let (x, si) = (fluid.points.get(slot), surfaces[slot]);
    let reference = 1.0 / w.value(c.spacing);
    // `Tᵢ` is the same in every pair: `Σⱼ Tᵢ · vⱼ = Tᵢ · Σⱼ vⱼ`, summed on lanes.
    let (mut own, mut to_walls, mut sum) = (Vec2::ZERO, Vec2::ZERO, Vec2::ZERO);
    // ∇ᵢWᵢⱼ hold on four lanes: −W'/r (xⱼ − xᵢ) (1 − ε f⁴).
    let held_gradients = |dx: Vec4, dy: Vec4, r2: Vec4| {
        let f = w.value_sq_x4(r2) * reference;
        let f2 = f * f;
        let scale = -slopes(g, c, r2) * (Vec4::ONE - HOLD * f2 * f2);
        (scale * dx, scale * dy)
    };
    if !si.is_dry() {
        walls.points.for_each_batch(x, |_, dx, dy, r2| {
            let (vx, vy) = held_gradients(dx, dy, r2);
            to_walls += Vec2::new(vx.element_sum(), vy.element_sum());
        });
    }
    let quiet = si.is_inside();
    fluid.points.for_each_batch(x, |first, dx, dy, r2| {
        let carry: [bool; LANES] = carries[first..first + LANES].try_into().unwrap_or_default();
        // Inside the liquid no one carries a stress: no kernel work.
        if quiet && carry == [false; LANES] {
            return;
        }
        let (vx, vy) = held_gradients(dx, dy, r2);
        if !quiet {
            own += Vec2::new(vx.element_sum(), vy.element_sum());
        }
        let (vx, vy) = (vx.to_array(), vy.to_array());
        for lane in 0..LANES {
            if carry[lane] {
                sum += surfaces[first + lane].stress(Vec2::new(vx[lane], vy[lane]));
            }
        }
    });
    sum + si.stress(own) + si.wall_stress(to_walls)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::kernels::{WendlandC2, lattice_sum};

    fn calibration(ratio: f32) -> SurfaceCalibration {
        let (dx, w) = (0.01, WendlandC2::new(ratio * 0.01));
        let volume = (1.0 / lattice_sum(&w, dx)) as f32;
        calibrate(&w, &w, dx, volume)
    }

    #[test]
    fn a_flat_surface_carries_about_half_the_delta_at_any_support() {
        for ratio in [2.0, 2.5, 3.0] {
            let s = calibration(ratio);
            // Continuum: the particles reach from c = 1 to c ≈ ½ (and half a spacing beyond).
            assert!((0.4..0.6).contains(&s.integral), "{ratio}: {s:?}");
            // The top row's gradient is of the order of 1/H.
            let h = ratio * 0.01;
            assert!((0.8..1.4).contains(&(s.top_row * h)), "{ratio}: {s:?}");
            // The hold takes a little off the pull between lattice neighbours.
            assert!((1.0..1.6).contains(&s.held), "{ratio}: {s:?}");
        }
    }
}
