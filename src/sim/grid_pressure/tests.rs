use super::laplacian::{CellKind, Laplacian};
use super::multigrid::Multigrid;
use super::pcg::Pcg;
use super::*;
use crate::sim::parallel::{PARALLEL_SLOTS, Rayon, Sequential};

const SPACING: f32 = 0.01;
const RHO: f32 = 1000.0;
const DT: f32 = 0.002;
const G: f32 = 9.81;

/// A block of particles on the rest lattice, `width` × `height` m from `(x0, 0)`.
fn block(x0: f32, width: f32, height: f32) -> Vec<Vec2> {
    let (columns, rows) = (
        (width / SPACING).round() as usize,
        (height / SPACING).round() as usize,
    );
    (0..rows)
        .flat_map(|j| {
            (0..columns).map(move |i| {
                Vec2::new(x0 + (i as f32 + 0.5) * SPACING, (j as f32 + 0.5) * SPACING)
            })
        })
        .collect()
}

/// The grid's input and the particles' velocities.
struct Input<'a> {
    grid: GridInput<'a>,
    velocities: &'a [Vec2],
}

fn input<'a>(positions: &'a [Vec2], velocities: &'a [Vec2], tank: Tank) -> Input<'a> {
    let grid = GridInput {
        ratios: &[],
        positions,
        spacing: SPACING,
        rest_density: RHO,
        gravity: Vec2::new(0.0, -G),
        tank: Some(tank),
    };
    Input { grid, velocities }
}

/// Prepares `grid` on `input`'s particles and solves for their velocities over [`DT`].
fn solve(
    grid: &mut GridPressure,
    input: &Input,
    solid: impl Fn(Vec2) -> Option<Vec2> + Sync,
    parallel: &impl Parallel,
) -> GridReport {
    grid.prepare(&input.grid, solid, parallel);
    grid.solve(&input.grid, input.velocities, DT, parallel)
}

/// The still column's predicted velocities: one step of gravity.
fn fallen(positions: &[Vec2]) -> Vec<Vec2> {
    vec![Vec2::new(0.0, -G * DT); positions.len()]
}

/// Solves a still column `depth` m deep across a 0.4 m tank and returns the grid with the
/// largest error of its fluid cells' pressure against `ρ₀ g (depth − y)`, Pa; with `per_cell`,
/// every fluid cell's is within 1% (or 1% of a spacing's head near the surface).
fn still_column(depth: f32, per_cell: bool) -> (GridPressure, f32) {
    let positions = block(0.0, 0.4, depth);
    let velocities = fallen(&positions);
    let mut grid = GridPressure::new(GridPressureSettings::default());
    let report = solve(
        &mut grid,
        &input(&positions, &velocities, Tank::new(0.4, 0.5)),
        |_| None,
        &Sequential,
    );
    assert!(report.relative_residual <= 1e-6, "{report:?}");
    let mut worst = 0.0f32;
    for c in 0..grid.equations.len() {
        if grid.equations.is_fluid(c) {
            let y = grid.center(c).y;
            let expected = RHO * G * (depth - y);
            let p = grid.pressure[c] as f32;
            assert!(
                !per_cell || (p - expected).abs() <= 0.01 * expected.max(RHO * G * SPACING),
                "cell at y = {y}: {p} Pa against {expected} Pa"
            );
            worst = worst.max((p - expected).abs());
        }
    }
    (grid, worst)
}

#[test]
fn a_still_column_holds_the_hydrostatic_pressure_in_every_fluid_cell() {
    let (grid, worst) = still_column(0.2, true);
    let fluid = grid.report().fluid_cells;
    // 0.4 m by 0.2 m of 2 cm cells: every one of them fluid, none above.
    assert_eq!(fluid, 20 * 10, "{:?}", grid.report());
    assert!(worst <= 0.01 * RHO * G * 0.01, "worst {worst} Pa");
    // Read back at the particles: the floor's pressure at the floor, none at the surface.
    let floor = grid.pressure_at(Vec2::new(0.2, 0.0));
    assert!(
        (floor - RHO * G * 0.2).abs() < 0.01 * RHO * G * 0.2,
        "{floor}"
    );
    let bottom = grid.pressure_at(Vec2::new(0.005, 0.005));
    assert!(
        (bottom - RHO * G * 0.195).abs() < 0.01 * RHO * G * 0.195,
        "{bottom}"
    );
    assert_eq!(grid.pressure_at(Vec2::new(0.2, 0.23)), 0.0);
    assert_eq!(grid.kind_at(Vec2::new(0.2, 0.19)), CellKind::Fluid);
    assert_eq!(grid.kind_at(Vec2::new(0.2, 0.21)), CellKind::Air);
    assert_eq!(grid.kind_at(Vec2::new(-0.01, 0.1)), CellKind::Solid);
}

#[test]
fn the_cells_fit_the_tank_width_and_a_still_column_stays_level() {
    // 0.41 m is 20.5 nominal cells of 2 cm: the cells shrink to 21 across.
    let positions = block(0.0, 0.41, 0.2);
    let velocities = fallen(&positions);
    let mut grid = GridPressure::new(GridPressureSettings::default());
    let tank = Tank::new(0.41, 0.5);
    solve(
        &mut grid,
        &input(&positions, &velocities, tank),
        |_| None,
        &Sequential,
    );
    assert!((grid.cell - 0.41 / 21.0).abs() < 1e-6, "{} m", grid.cell);
    assert_eq!(cell_size(0.02, None), 0.02);
    // Every row of fluid cells at one pressure, the last column against the wall included.
    let nx = grid.equations.nx;
    for row in 0..grid.equations.ny {
        let fluid: Vec<f64> = (row * nx..(row + 1) * nx)
            .filter(|&c| grid.equations.is_fluid(c))
            .map(|c| grid.pressure[c])
            .collect();
        let (lo, hi) = fluid
            .iter()
            .fold((f64::MAX, f64::MIN), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        assert!(
            fluid.is_empty() || hi - lo <= 0.005 * f64::from(RHO * G * 0.2),
            "row {row}: {lo}..{hi} Pa"
        );
    }
}

#[test]
fn a_column_off_the_cells_lattice_finds_its_surface_within_a_third_of_a_spacing() {
    // A surface inside a cell is found from the cells' fills (the ghost-fluid method), so the
    // error is a shift of the whole column's head: held to a third of a spacing's.
    for depth in [0.21, 0.25, 0.33] {
        let (_, worst) = still_column(depth, false);
        assert!(
            worst <= RHO * G * SPACING / 3.0,
            "depth {depth}: worst {worst} Pa"
        );
    }
}

/// Each fluid cell's divergence after the projection, from the faces' velocities
/// `u − (dt/ρ₀) ∇p` computed face by face, 1/s.
fn projected_divergence(grid: &GridPressure) -> Vec<f32> {
    let e = &grid.equations;
    let scale = DT / RHO / grid.cell;
    let pressure = |c: usize, n: Option<usize>| -> Option<f32> {
        let p = grid.pressure[c] as f32;
        match e.kind_of(n) {
            CellKind::Solid => None,
            CellKind::Fluid => Some(grid.pressure[n.unwrap()] as f32),
            CellKind::Air => Some(p * (1.0 - 1.0 / theta(grid.fill[c], grid.fill[n.unwrap()]))),
        }
    };
    (0..e.len())
        .filter(|&c| e.is_fluid(c))
        .map(|c| {
            let (i, j, nx) = (c % e.nx, c / e.nx, e.nx);
            let [left, right, down, up] = e.neighbors(c);
            let p = grid.pressure[c] as f32;
            // Outward velocity through each face: u* minus the pressure's push.
            let out = |u: f32, sign: f32, n: Option<usize>| {
                let push = pressure(c, n).map_or(0.0, |q| scale * (q - p));
                sign * u - push
            };
            let faces = &grid.faces;
            (out(faces[0][j * (nx + 1) + i + 1], 1.0, right)
                + out(faces[0][j * (nx + 1) + i], -1.0, left)
                + out(faces[1][(j + 1) * nx + i], 1.0, up)
                + out(faces[1][j * nx + i], -1.0, down))
                / grid.cell
        })
        .collect()
}

/// A dam-break block in motion, a swirl on a fall, beside a disc moving through it.
fn moving_block() -> (Vec<Vec2>, Vec<Vec2>) {
    let positions = block(0.0, 0.3, 0.4);
    let velocities = positions
        .iter()
        .map(|x| {
            let r = *x - Vec2::new(0.15, 0.2);
            Vec2::new(-r.y, r.x) * 3.0 + Vec2::new(0.4 * (20.0 * x.y).sin(), -G * DT)
        })
        .collect();
    (positions, velocities)
}

fn moving_disc(x: Vec2) -> Option<Vec2> {
    (x.distance(Vec2::new(0.2, 0.15)) < 0.05).then_some(Vec2::new(0.3, -0.1))
}

#[test]
fn the_projected_velocity_is_divergence_free_with_walls_a_surface_and_a_moving_solid() {
    let (positions, velocities) = moving_block();
    let mut grid = GridPressure::new(GridPressureSettings::default());
    let report = solve(
        &mut grid,
        &input(&positions, &velocities, Tank::new(0.8, 0.5)),
        moving_disc,
        &Sequential,
    );
    assert!(
        report.fluid_cells > 250 && report.iterations > 0,
        "{report:?}"
    );
    assert!(report.relative_residual <= 1e-6, "{report:?}");
    let solid = (0..grid.equations.len())
        .filter(|&c| grid.equations.kind[c] == CellKind::Solid && grid.center(c).x > 0.0)
        .filter(|&c| grid.center(c).x < 0.8 && grid.center(c).y > 0.0);
    assert!(solid.count() >= 16, "the disc is solid cells");
    let before = (0..grid.equations.len())
        .filter(|&c| grid.equations.is_fluid(c))
        .map(|c| divergence(&grid.faces, c, (grid.equations.nx, 0), grid.cell).abs())
        .fold(0.0f32, f32::max);
    let after = projected_divergence(&grid)
        .into_iter()
        .fold(0.0f32, |m, d| m.max(d.abs()));
    assert!(before > 1.0, "the velocities diverge before: {before} 1/s");
    assert!(
        after <= 1e-4 * before,
        "after {after} 1/s, before {before} 1/s"
    );
}

#[test]
fn the_disc_s_velocity_is_felt_by_the_pressure() {
    let positions = block(0.0, 0.4, 0.3);
    let velocities = fallen(&positions);
    let tank = Tank::new(0.4, 0.5);
    let (mut still, mut moving) = (GridPressure::default(), GridPressure::default());
    still.settings = GridPressureSettings::default();
    moving.settings = GridPressureSettings::default();
    let disc = |v: Vec2| move |x: Vec2| (x.distance(Vec2::new(0.2, 0.15)) < 0.05).then_some(v);
    solve(
        &mut still,
        &input(&positions, &velocities, tank),
        disc(Vec2::ZERO),
        &Sequential,
    );
    let up = Vec2::new(0.0, 0.2);
    solve(
        &mut moving,
        &input(&positions, &velocities, tank),
        disc(up),
        &Sequential,
    );
    // A disc rising pushes the water above it and draws the water below.
    let (above, below) = (Vec2::new(0.2, 0.23), Vec2::new(0.2, 0.07));
    assert!(moving.pressure_at(above) > still.pressure_at(above) + 50.0);
    assert!(moving.pressure_at(below) < still.pressure_at(below) - 50.0);
}

#[test]
fn a_pocket_sealed_by_a_solid_is_left_to_the_particles() {
    // Water everywhere in the tank, and a solid arch on the floor rising off the water it
    // traps: the pocket's equations have no solution (no face lets water in).
    let centre = Vec2::new(0.2, 0.0);
    let arch = move |x: Vec2| {
        let r = x.distance(centre);
        (0.05..0.1).contains(&r).then_some(Vec2::new(0.0, 0.005))
    };
    let positions: Vec<Vec2> = block(0.0, 0.4, 0.3)
        .into_iter()
        .filter(|&x| arch(x).is_none())
        .collect();
    let velocities = fallen(&positions);
    let mut grid = GridPressure::new(GridPressureSettings::default());
    let report = solve(
        &mut grid,
        &input(&positions, &velocities, Tank::new(0.4, 0.5)),
        arch,
        &Sequential,
    );
    assert!(report.relative_residual <= 1e-6, "{report:?}");
    let pocket = centre + Vec2::new(0.0, 0.02);
    assert_eq!(grid.kind_at(pocket), CellKind::Air, "the pocket is open");
    assert_eq!(grid.pressure_at(pocket), 0.0);
    // The water round the arch keeps its weight.
    for x in [
        Vec2::new(0.03, 0.05),
        Vec2::new(0.37, 0.15),
        Vec2::new(0.2, 0.25),
    ] {
        let expected = RHO * G * (0.3 - x.y);
        let p = grid.pressure_at(x);
        assert!(
            p.is_finite() && (p - expected).abs() <= 0.1 * expected + RHO * G * SPACING,
            "{p} Pa at {x}, {expected} expected"
        );
    }
}

/// The equations of an `n` × `n` box: solid walls a cell thick, the lower three fifths fluid,
/// air above.
fn tank_equations(n: usize) -> Laplacian {
    let kind = (0..n * n)
        .map(|c| {
            let (i, j) = (c % n, c / n);
            if i == 0 || j == 0 || i == n - 1 || j == n - 1 {
                CellKind::Solid
            } else if j < 3 * n / 5 {
                CellKind::Fluid
            } else {
                CellKind::Air
            }
        })
        .collect();
    let mut equations = Laplacian {
        nx: n,
        ny: n,
        kind,
        diag: vec![0.0; n * n],
        off: (n * n) as f32,
        ..Laplacian::default()
    };
    equations.set_plain_diagonal();
    equations.number_unknowns();
    equations
}

/// A right-hand side with every wavelength in it, the same on every run.
fn rough_rhs(equations: &Laplacian) -> Vec<f64> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    (0..equations.len())
        .map(|c| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let value = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            if equations.is_fluid(c) { value } else { 0.0 }
        })
        .collect()
}

#[test]
fn the_v_cycles_a_solve_takes_do_not_grow_with_the_grid() {
    let counts: Vec<u32> = [32, 64, 128, 256, 512]
        .into_iter()
        .map(|n| {
            let equations = tank_equations(n);
            let b = rough_rhs(&equations);
            let mut multigrid = Multigrid::default();
            multigrid.rebuild(&equations);
            let mut x = vec![0.0; equations.len()];
            let result = Pcg::default().solve(
                (&equations, &mut multigrid),
                &b,
                &mut x,
                (1e-6, 200),
                &Sequential,
            );
            assert!(result.relative_residual <= 1e-6, "{n}²: {result:?}");
            result.iterations
        })
        .collect();
    let (fewest, most) = (counts.iter().min().unwrap(), counts.iter().max().unwrap());
    assert!(
        *most <= fewest + 4 && *most <= 30,
        "V-cycles from 32² to 512²: {counts:?}"
    );
}

#[test]
fn the_pressure_is_the_same_on_any_number_of_threads() {
    let (positions, velocities) = moving_block();
    let tank = Tank::new(0.8, 0.5);
    let mut one = GridPressure::new(GridPressureSettings {
        cell_ratio: 1.0,
        ..GridPressureSettings::default()
    });
    let mut two = one.clone();
    solve(
        &mut one,
        &input(&positions, &velocities, tank),
        moving_disc,
        &Sequential,
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    pool.install(|| {
        solve(
            &mut two,
            &input(&positions, &velocities, tank),
            moving_disc,
            &Rayon,
        )
    });
    // Enough cells that the cell passes run in parallel chunks.
    assert!(
        one.report().fluid_cells > PARALLEL_SLOTS,
        "{:?}",
        one.report()
    );
    assert_eq!(one.report(), two.report());
    assert_eq!(one.pressure, two.pressure);
    assert_eq!(one.extended, two.extended);
}

#[test]
fn the_last_pressure_starts_the_next_solve_unless_forgotten() {
    let positions = block(0.0, 0.4, 0.3);
    let velocities = fallen(&positions);
    let tank = Tank::new(0.4, 0.5);
    let mut grid = GridPressure::new(GridPressureSettings::default());
    let cold = solve(
        &mut grid,
        &input(&positions, &velocities, tank),
        |_| None,
        &Sequential,
    );
    let warm = solve(
        &mut grid,
        &input(&positions, &velocities, tank),
        |_| None,
        &Sequential,
    );
    grid.forget();
    let forgotten = solve(
        &mut grid,
        &input(&positions, &velocities, tank),
        |_| None,
        &Sequential,
    );
    assert!(cold.iterations >= 3, "{cold:?}");
    assert!(warm.iterations <= 1, "{warm:?}");
    assert_eq!(forgotten, cold);
}

#[test]
fn no_particles_or_broken_ones_give_no_grid_and_no_pressure() {
    let mut grid = GridPressure::default();
    let tank = Tank::new(0.4, 0.5);
    let report = solve(&mut grid, &input(&[], &[], tank), |_| None, &Sequential);
    assert_eq!(report.cells, 0);
    assert_eq!(grid.pressure_at(Vec2::new(0.1, 0.1)), 0.0);
    let mut positions = block(0.0, 0.4, 0.1);
    positions[3] = Vec2::NAN;
    positions[4] = Vec2::splat(1e30);
    let mut velocities = fallen(&positions);
    velocities[5] = Vec2::new(f32::INFINITY, 0.0);
    grid = GridPressure::new(GridPressureSettings::default());
    let report = solve(
        &mut grid,
        &input(&positions, &velocities, tank),
        |_| None,
        &Sequential,
    );
    assert!(report.cells > 0 && report.cells <= 22 * 27, "{report:?}");
    let p = grid.pressure_at(Vec2::new(0.2, 0.01));
    assert!(p.is_finite() && p > 0.5 * RHO * G * 0.1, "{p}");
}
