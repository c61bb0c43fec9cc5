//! Surface tension (experimental), on the plain-vector driver: a weightless block of water rounds
//! up and oscillates at the Rayleigh period of a 2D drop, holding together and keeping its
//! momentum.

use bevy::math::Vec2;
use bevy_sph2d::fluid::SphParams;
use bevy_sph2d::gameplay::FluidBlock;
use bevy_sph2d::slices::SliceFluid;

/// Water's surface tension, N/m.
const SIGMA: f32 = 0.072;

/// A weightless block of water of the area of a disc of `radius` (m), `aspect` times as wide
/// as high, centred on the origin, at 1 mm spacing.
fn weightless_block(radius: f32, aspect: f32) -> SliceFluid {
    let params = SphParams {
        particle_spacing: 0.001,
        tank: None,
        gravity: Vec2::ZERO,
        surface_tension: SIGMA,
        ..SphParams::water()
    };
    let area = core::f32::consts::PI * radius * radius;
    let width = (area * aspect).sqrt();
    let size = Vec2::new(width, area / width);
    let block = FluidBlock::new(-size / 2.0, size);
    SliceFluid::new(
        params.constants().expect("valid"),
        block.positions_for(&params),
    )
}

/// The centre of mass and the ellipticity `(Ixx − Iyy)/(Ixx + Iyy)` of the particles' second
/// moments: positive while the drop is wider than high.
fn shape(f: &SliceFluid) -> (Vec2, f32) {
    let centre = f.position.iter().sum::<Vec2>() / f.len() as f32;
    let (xx, yy) = f.position.iter().fold((0.0, 0.0), |(xx, yy), p| {
        let d = *p - centre;
        (xx + d.x * d.x, yy + d.y * d.y)
    });
    (centre, (xx - yy) / (xx + yy))
}

/// A 2:1 block of the area of a 2 cm disc, released without gravity, rounds up and overshoots:
/// its lowest shape mode's period, from the zero crossings of the ellipticity over 2.5 s, is
/// within 15% of `2π/ω` with `ω² = 6σ/(ρR³)` (0.855 s; measured 0.843 s). Nothing leaves
/// the drop, no two particles come closer than half a spacing, and its momentum stays nil.
#[test]
fn a_weightless_block_oscillates_at_the_rayleigh_period() {
    let radius = 0.02;
    let mut drop = weightless_block(radius, 2.0);
    let tick = 0.01;
    let (mut crossings, mut last) = (Vec::new(), shape(&drop).1);
    for k in 1..=250 {
        drop.advance(tick);
        let e = shape(&drop).1;
        if e.signum() != last.signum() {
            // Interpolated within the tick.
            crossings.push(k as f64 * tick - tick * (e / (e - last)) as f64);
        }
        last = e;
    }
    assert!(crossings.len() >= 5, "it does not oscillate: {crossings:?}");
    let periods: Vec<f64> = crossings.windows(3).map(|w| w[2] - w[0]).collect();
    let measured = periods.iter().sum::<f64>() / periods.len() as f64;
    let omega = (6.0 * SIGMA as f64 / (1000.0 * (radius as f64).powi(3))).sqrt();
    let theory = core::f64::consts::TAU / omega;
    println!("periods {periods:.3?}: mean {measured:.3} s against {theory:.3} s");
    assert!(
        (measured / theory - 1.0).abs() < 0.15,
        "period {measured:.3} s against Rayleigh's {theory:.3} s"
    );

    let (centre, _) = shape(&drop);
    let strays = drop
        .position
        .iter()
        .filter(|p| p.distance(centre) > 2.0 * radius)
        .count();
    assert_eq!(strays, 0, "particles left the drop");
    let mut closest = f32::MAX;
    for (i, a) in drop.position.iter().enumerate() {
        for b in &drop.position[i + 1..] {
            closest = closest.min(a.distance(*b));
        }
    }
    assert!(closest > 0.0005, "particles pair up: {closest} m apart");
    // Pairwise pulls: the drop's mean velocity stays at rounding's level against the scale of
    // its flows, √(σ/ρR) = 6 cm/s.
    let drift = drop.velocity.iter().sum::<Vec2>() / drop.len() as f32;
    assert!(drift.length() < 1e-4, "the drop drifts at {drift} m/s");
    assert_eq!(drop.non_finite(), 0);
}
