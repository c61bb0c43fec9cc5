//! The laminar viscosity between two liquids of their own viscosities: both solvers' pair terms
//! (Lo & Shao 2002, `4ν (r·∇W)/((ρᵢ+ρⱼ)(r²+η²)) vᵢⱼ` per unit of the neighbour's mass) take a
//! pair's `ν` as the harmonic mean of the two particles' ([`pair_laminar`]), so a pair of one
//! liquid has that liquid's `ν`, and at the surface between a thin and a thick liquid the
//! thin one sets the shear, as the stress continuous across a layered flow does (Hu & Adams
//! 2006 take the same mean of the dynamic viscosities).

use super::layout::FluidSnapshot;
use bevy::math::Vec4;

/// `4 νᵢⱼ` for a particle of viscosity `nu_i` and four neighbours of `nu_j` (m²/s), with
/// `νᵢⱼ = 2νᵢνⱼ/(νᵢ+νⱼ)` (zero when both are inviscid).
#[inline(always)]
pub fn pair_laminar(nu_i: f32, nu_j: Vec4) -> Vec4 {
    let nu_i = Vec4::splat(nu_i);
    Vec4::splat(8.0) * nu_i * nu_j / (nu_i + nu_j).max(Vec4::splat(f32::MIN_POSITIVE))
}

/// The laminar coefficients of a particle's pairs, read from the snapshot: the base liquid's
/// `4ν` for every pair while every particle has it, else [`pair_laminar`] by slot.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Laminar<'a> {
    /// Viscosity by sorted slot (see [`FluidSnapshot::viscosity`]); empty for the base one.
    by_slot: &'a [f32],
    /// The particle's own `ν`, m²/s.
    own: f32,
    /// The base liquid's `4ν` in every lane.
    uniform: Vec4,
}

impl<'a> Laminar<'a> {
    /// The coefficients for the particle at sorted `slot` with the base viscosity `nu`.
    #[inline]
    pub fn at(fluid: &'a FluidSnapshot, nu: f32, slot: usize) -> Self {
        let by_slot = fluid.viscosity.as_slice();
        Self {
            by_slot,
            own: by_slot.get(slot).copied().unwrap_or(nu),
            uniform: Vec4::splat(4.0 * nu),
        }
    }

    /// `4ν` of the particle's own (its walls' friction).
    #[inline]
    pub fn own(&self) -> f32 {
        4.0 * self.own
    }

    /// `4νᵢⱼ` with four neighbours, whose viscosities `gather` reads from the viscosities by
    /// sorted slot (called only when the particles have their own).
    #[inline(always)]
    pub fn lanes(&self, gather: impl FnOnce(&[f32]) -> Vec4) -> Vec4 {
        if self.by_slot.is_empty() {
            self.uniform
        } else {
            pair_laminar(self.own, gather(self.by_slot))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_liquid_keeps_its_viscosity_and_the_thin_liquid_sets_a_mixed_pair() {
        let same = pair_laminar(1e-6, Vec4::splat(1e-6));
        assert!((same.x - 4e-6).abs() < 1e-12, "{same}");
        let mixed = pair_laminar(1e-6, Vec4::splat(5e-5));
        assert!(mixed.x > 4e-6 && mixed.x < 8e-6, "{mixed}");
        assert_eq!(pair_laminar(0.0, Vec4::ZERO), Vec4::ZERO);
        assert_eq!(pair_laminar(0.0, Vec4::splat(1e-3)), Vec4::ZERO);
    }
}
