mod common;
use bevy_sph2d::fluid::scenario::SCENARIO_TANK;
use bevy_sph2d::fluid::slices::SliceFluid;
use bevy_sph2d::fluid::{ScenarioKind, SphParams, SphScenario};
#[test]
fn dbg3() {
    let n: u32 = std::env::var("N")
        .map(|v| v.parse().unwrap())
        .unwrap_or(2500);
    let scenario = SphScenario::new(ScenarioKind::DamBreak, n);
    let tank = SCENARIO_TANK;
    let mut params = SphParams {
        tank: Some(tank),
        particle_spacing: scenario.spacing(&tank),
        max_substeps: 100000,
        ..common::dfsph_water()
    };
    if let Ok(v) = std::env::var("AV") {
        params.artificial_viscosity = v.parse().unwrap();
    }
    if let Ok(v) = std::env::var("CFL") {
        params.dfsph.cfl_number = v.parse().unwrap();
    }
    if let Ok(v) = std::env::var("DIV") {
        params.dfsph.divergence_tolerance = v.parse().unwrap();
    }
    if let Ok(v) = std::env::var("TOL") {
        params.dfsph.density_tolerance = v.parse().unwrap();
    }
    if let Ok(v) = std::env::var("KS") {
        params.kernel = match v.as_str() {
            "cubic" => bevy_sph2d::fluid::KernelKind::CubicSpline,
            _ => bevy_sph2d::fluid::KernelKind::WendlandC2,
        };
    }
    if let Ok(v) = std::env::var("RATIO") {
        params.support_ratio = v.parse().unwrap();
    }
    let mut positions = Vec::new();
    for b in scenario.blocks(&tank) {
        positions.extend(b.positions_for(&params));
    }
    let mut fluid = SliceFluid::new(params.constants().unwrap(), positions, &[]);
    let mut worst = 0.0f32;
    let mut steps = 0;
    while fluid.clock.time < 1.5 {
        fluid.step();
        steps += 1;
        let vmax = fluid
            .velocity
            .iter()
            .map(|v| v.length())
            .fold(0.0f32, f32::max);
        worst = worst.max(vmax);
        let kmax = fluid.stiffness.iter().map(|k| k.x).fold(0.0f32, f32::max);
        if steps > 240 || steps % 40 == 0 {
            println!(
                "step {steps} t {:.4} dt {:.5} kmax {kmax:.2} vmax {vmax:.2} it {}",
                fluid.clock.time, fluid.clock.dt, fluid.iterations
            );
        }
        if vmax > 12.0 {
            println!(
                "BLOWUP at t {:.3} vmax {vmax} dt {}",
                fluid.clock.time, fluid.clock.dt
            );
            let mut idx: Vec<usize> = (0..fluid.len()).collect();
            idx.sort_by(|&a, &b| {
                fluid.velocity[b]
                    .length()
                    .total_cmp(&fluid.velocity[a].length())
            });
            for &i in idx.iter().take(6) {
                let near = fluid
                    .position
                    .iter()
                    .filter(|q| (**q - fluid.position[i]).length() < 0.0255)
                    .count();
                println!(
                    "  x {} v {} rho {} p {} k {} near {near}",
                    fluid.position[i],
                    fluid.velocity[i],
                    fluid.density[i],
                    fluid.pressure[i],
                    fluid.stiffness[i]
                );
            }
            break;
        }
    }
    println!(
        "RESULT t {:.3} steps {steps} worst {worst:.2} iterations/step {:.1}",
        fluid.clock.time,
        fluid.iterations as f64 / steps as f64
    );
}
