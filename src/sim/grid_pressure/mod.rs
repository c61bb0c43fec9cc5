//! A pressure solved on a coarse grid under the particles: the smooth, fluid-wide part of the
//! pressure that local SPH iterations remove slowest (a column's weight), at a cost that does
//! not grow with the depth. Pure, no ECS; the DFSPH density solve starts from it
//! ([`DfsphSettings::grid_start`](super::config::DfsphSettings::grid_start)).
//!
//! Each solve ([`GridPressure::prepare`], steps 1 and 2 and the equations of step 4 from the
//! positions alone; then [`GridPressure::solve`] with the velocities):
//! 1. A rectangle of square cells of [`GridPressureSettings::cell_ratio`] particle spacings
//!    (fitted to a whole number across the tank's width, so its side walls lie on cell faces),
//!    on a lattice fixed to the world's origin (the tank's inner corner), bounded to the
//!    particles and padded by two cells (and to the tank and its walls).
//! 2. Cells whose centre lies outside the tank or inside a solid are solid, with the solid's
//!    velocity; the particles' volumes are spread bilinearly over the cell centres (a share that
//!    falls on a solid cell stays in the particle's own cell, the wall's mirror image), and a
//!    cell at least half full is fluid, the rest air.
//! 3. The particles' (predicted) velocities are averaged bilinearly onto the cell faces (a MAC
//!    grid); a face of a solid cell carries the solid's velocity.
//! 4. The pressure `p` that makes the faces' velocity `u − (dt/ρ₀) ∇p` divergence-free in every
//!    fluid cell: `−∇²p = −(ρ₀/dt) ∇·u` on the five-point stencil, zero pressure at the free
//!    surface, which lies between a fluid cell and an air neighbour where the fill's level set
//!    `φ = ½ − fill` crosses zero (the ghost-fluid method: Gibou et al. 2002, as in Enright,
//!    Nguyen, Gibou & Fedkiw 2003), no flow through solids but their own. The equations are
//!    solved by conjugate gradients preconditioned with a multigrid V-cycle (McAdams, Sifakis &
//!    Teran 2010), warm-started from the last solve's pressure cell by cell unless told to
//!    [`forget`](GridPressure::forget) it.
//! 5. [`GridPressure::pressure_at`] reads the pressure back at any point, bilinearly between
//!    cell centres, from a field extended past the fluid: into solid cells hydrostatically
//!    (`p + ρ₀ g·Δx` from the fluid neighbour, so a particle at the floor reads the floor's
//!    pressure), into air cells by the ghost-fluid line through zero at the surface, clamped at
//!    zero (pressure pushes, never pulls).
//!
//! The pressure sums run in f64 and the preconditioner in f32; every sum is taken in a fixed
//! order, so the pressure is the same on any number of threads.

mod laplacian;
mod multigrid;
mod pcg;
mod splat;

pub use laplacian::CellKind;

use super::boundary::Tank;
use super::parallel::Parallel;
use bevy::math::{IVec2, Vec2};
use laplacian::Laplacian;
use multigrid::Multigrid;
use pcg::Pcg;
use splat::{Band, SplatInput, floor};

/// A free-surface fraction `θ` (the way from a fluid cell's centre to its air neighbour's where
/// the surface lies) is at least this: a surface right at a centre would make its equation
/// stiff without changing the pressure it gives.
const MIN_THETA: f32 = 0.1;

/// A grid of more cells than this is not built ([`GridReport::cells`] reads zero): particles
/// scattered that far apart have no pressure worth a grid.
pub const MAX_CELLS: usize = 1 << 22;

/// How the grid pressure is solved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridPressureSettings {
    /// A cell's side in particle spacings.
    pub cell_ratio: f32,
    /// The solve stops when the largest residual is this fraction of the largest right-hand
    /// side (the divergence of the faces' velocities).
    pub tolerance: f32,
    /// At most this many conjugate-gradient iterations (V-cycles) a solve.
    pub max_iterations: u32,
}

impl Default for GridPressureSettings {
    fn default() -> Self {
        Self {
            cell_ratio: 2.0,
            tolerance: 1e-6,
            max_iterations: 100,
        }
    }
}

/// What one solve reads of the fluid besides its velocities: the grid's geometry.
#[derive(Debug, Clone, Copy)]
pub struct GridInput<'a> {
    /// Particle positions, m.
    pub positions: &'a [Vec2],
    /// The particle spacing, m (a particle's volume is its square).
    pub spacing: f32,
    /// Rest density, kg/m³.
    pub rest_density: f32,
    /// Gravity, m/s² (the pressure's extension into solid cells).
    pub gravity: Vec2,
    /// The tank, if any: cells outside it are solid.
    pub tank: Option<Tank>,
    /// Each particle's rest density over `rest_density`, by the order of `positions`; empty
    /// for one liquid.
    pub ratios: &'a [f32],
}

/// What the last solve did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GridReport {
    /// Cells of the grid.
    pub cells: usize,
    /// Of those, fluid.
    pub fluid_cells: usize,
    /// Levels of the multigrid.
    pub levels: usize,
    /// Conjugate-gradient iterations (one V-cycle each).
    pub iterations: u32,
    /// The largest residual left, as a fraction of the largest right-hand side.
    pub relative_residual: f32,
}

/// The pressure of the last solve and the last solve's last pressure, cell by cell, with the
/// grid's own state (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct GridPressure {
    settings: GridPressureSettings,
    /// A cell's side, m.
    cell: f32,
    /// The lattice index of the rectangle's first cell.
    first: IVec2,
    equations: Laplacian,
    fill: Vec<f32>,
    solid_velocity: Vec<Vec2>,
    /// Velocities on the faces normal to x (`(nx + 1) ny`) and to y (`nx (ny + 1)`), m/s.
    faces: [Vec<f32>; 2],
    /// Scratch of the faces: each one's weighted velocity sum and weight.
    face_sums: [Vec<[f32; 2]>; 2],
    /// Scratch of the splat: its runs of particles and their sums.
    bands: Vec<Band>,
    rhs: Vec<f64>,
    /// Pressure per fluid cell, Pa (zero elsewhere).
    pressure: Vec<f64>,
    /// The pressure extended past the fluid for reading back, Pa.
    extended: Vec<f32>,
    /// The last solve's pressure, for the next one's start.
    previous: (IVec2, usize, Vec<f64>),
    multigrid: Multigrid,
    pcg: Pcg,
    /// Scratch of the cell passes: a flag per cell and a list of cells.
    scratch: (Vec<bool>, Vec<usize>),
    /// `ρ₀ g`, Pa/m.
    weight: Vec2,
    /// Whether [`prepare`](GridPressure::prepare) built a grid for the next solve.
    prepared: bool,
    report: GridReport,
}

impl GridPressure {
    /// A grid pressure solved with `settings`.
    pub fn new(settings: GridPressureSettings) -> Self {
        Self {
            settings,
            ..Self::default()
        }
    }

    /// What the last solve did.
    #[cfg(test)]
    pub fn report(&self) -> GridReport {
        self.report
    }

    /// Steps 1 and 2 and the equations of step 4, all that reads the positions alone: the
    /// rectangle of cells over `input`'s particles, the solid cells (`solid(x)` gives the
    /// velocity of the solid at `x`, if any, besides the tank), the fill, the fluid cells and
    /// their equations with the multigrid's levels. Returns whether there is a grid (none for
    /// no finite particle, or more than [`MAX_CELLS`]); [`solve`](Self::solve) then solves on
    /// it. Runs beside other work (the neighbour pass) as the velocities are made.
    pub fn prepare(
        &mut self,
        input: &GridInput,
        solid: impl Fn(Vec2) -> Option<Vec2> + Sync,
        parallel: &impl Parallel,
    ) -> bool {
        self.report = GridReport::default();
        self.cell = cell_size(self.settings.cell_ratio * input.spacing, input.tank);
        self.weight = input.rest_density * input.gravity;
        self.prepared = self.place(input);
        if !self.prepared {
            self.equations = Laplacian::default();
            self.pressure.clear();
            self.extended.clear();
            return false;
        }
        self.classify(input.tank, &solid, parallel);
        self.splat_fill(input, parallel);
        self.splat_ratios(input);
        self.assemble_equations();
        self.multigrid.rebuild(&self.equations);
        true
    }

    /// Solves the pressure that makes `velocities` (the particles' of the `input` the grid was
    /// [`prepare`](Self::prepare)d from, predicted under every other force, m/s)
    /// divergence-free over a step of `dt` seconds (see the module docs). Each solve needs a
    /// [`prepare`](Self::prepare) of its own: without one there is no pressure (it reads zero
    /// everywhere).
    pub fn solve(
        &mut self,
        input: &GridInput,
        velocities: &[Vec2],
        dt: f32,
        parallel: &impl Parallel,
    ) -> GridReport {
        if !core::mem::take(&mut self.prepared) {
            self.pressure.clear();
            self.extended.clear();
            self.report = GridReport::default();
            return self.report;
        }
        self.splat_faces(input, velocities, parallel);
        self.assemble_rhs(input.rest_density, dt);
        self.warm_start();
        let result = self.pcg.solve(
            (&self.equations, &mut self.multigrid),
            &self.rhs,
            &mut self.pressure,
            (
                f64::from(self.settings.tolerance),
                self.settings.max_iterations,
            ),
            parallel,
        );
        if result.relative_residual.is_nan() || result.relative_residual > 1.0 {
            // Diverged (the equations are singular only in a sealed pocket, which
            // `assemble_equations` opens; this is the net under it): no pressure rather than a
            // wrong one.
            self.pressure.fill(0.0);
        }
        self.extend();
        self.previous.0 = self.first;
        self.previous.1 = self.equations.nx;
        self.previous.2.clone_from(&self.pressure);
        self.report = GridReport {
            cells: self.equations.len(),
            fluid_cells: self.equations.unknowns(),
            levels: self.multigrid.depth(),
            iterations: result.iterations,
            relative_residual: result.relative_residual as f32,
        };
        self.report
    }

    /// Forgets the last solve's pressure: the next solve starts from zero, as the first did.
    pub fn forget(&mut self) {
        self.previous.2.clear();
    }

    /// The pressure at `x`, Pa: bilinear between the cell centres of the last solve, extended
    /// past the fluid (see the module docs), never negative; zero off the grid.
    pub fn pressure_at(&self, x: Vec2) -> f32 {
        if self.extended.is_empty() {
            return 0.0;
        }
        let g = x / self.cell - self.first.as_vec2() - Vec2::splat(0.5);
        let base = floor(g);
        let f = g - base;
        let (i, j) = (base.x as i64, base.y as i64);
        let value = |di: i64, dj: i64| self.cell_value(i + di, j + dj);
        let p = (1.0 - f.y) * ((1.0 - f.x) * value(0, 0) + f.x * value(1, 0))
            + f.y * ((1.0 - f.x) * value(0, 1) + f.x * value(1, 1));
        p.max(0.0)
    }

    /// The pressure of cell `(i, j)` of the rectangle, Pa: the solved one in the fluid, the
    /// extended one elsewhere, zero outside.
    fn cell_value(&self, i: i64, j: i64) -> f32 {
        let (nx, ny) = (self.equations.nx as i64, self.equations.ny as i64);
        if i < 0 || j < 0 || i >= nx || j >= ny {
            return 0.0;
        }
        self.extended[(j * nx + i) as usize]
    }

    /// The kind of the cell holding `x` in the last solve (air off the grid).
    #[cfg(test)]
    pub fn kind_at(&self, x: Vec2) -> CellKind {
        self.cell_index(x)
            .map_or(CellKind::Air, |c| self.equations.kind[c])
    }

    /// The rectangle's index of the cell holding `x`, if it is on the grid.
    #[cfg(test)]
    fn cell_index(&self, x: Vec2) -> Option<usize> {
        let g = (x / self.cell).floor() - self.first.as_vec2();
        let (nx, ny) = (self.equations.nx as f32, self.equations.ny as f32);
        (g.x >= 0.0 && g.y >= 0.0 && g.x < nx && g.y < ny)
            .then(|| g.y as usize * self.equations.nx + g.x as usize)
    }

    /// Step 1: the rectangle of cells; `false` if there is none (no finite particle, or more
    /// than [`MAX_CELLS`]).
    fn place(&mut self, input: &GridInput) -> bool {
        let (mut lo, mut hi) = (Vec2::splat(f32::MAX), Vec2::splat(f32::MIN));
        for &x in input.positions.iter().filter(|x| x.is_finite()) {
            (lo, hi) = (lo.min(x), hi.max(x));
        }
        if lo.x > hi.x || self.cell.is_nan() || self.cell <= 0.0 {
            return false;
        }
        // In cells, clamped to the tank before any conversion to integers (a particle flung far
        // away must not overflow them).
        let (mut first, mut last) = (
            (lo / self.cell).floor() - Vec2::splat(2.0),
            (hi / self.cell).floor() + Vec2::splat(2.0),
        );
        if let Some(tank) = input.tank {
            // The tank's walls are the cells just outside it.
            let end = (tank.size() / self.cell).ceil();
            first = first.clamp(Vec2::NEG_ONE, end);
            last = last.clamp(Vec2::NEG_ONE, end);
        }
        let size = (last - first + Vec2::ONE).max(Vec2::ZERO);
        let area = size.x * size.y;
        if area.is_nan() || area > MAX_CELLS as f32 || area < 1.0 {
            return false;
        }
        let (first, size) = (first.as_ivec2(), size.as_uvec2());
        let cells = size.x as usize * size.y as usize;
        self.first = first;
        let e = &mut self.equations;
        (e.nx, e.ny, e.off) = (size.x as usize, size.y as usize, self.cell.powi(-2));
        for v in [&mut e.diag, &mut self.fill] {
            v.clear();
            v.resize(cells, 0.0);
        }
        e.kind.clear();
        e.kind.resize(cells, CellKind::Air);
        true
    }

    /// The centre of cell `c` of the rectangle, m.
    fn center(&self, c: usize) -> Vec2 {
        let nx = self.equations.nx;
        cell_center((self.first, self.cell), (c % nx, c / nx))
    }

    /// Step 2, the solids: cells outside the tank or inside a solid, with their velocities.
    fn classify(
        &mut self,
        tank: Option<Tank>,
        solid: &(impl Fn(Vec2) -> Option<Vec2> + Sync),
        parallel: &impl Parallel,
    ) {
        let cells = self.equations.len();
        self.solid_velocity.clear();
        self.solid_velocity.resize(cells, Vec2::ZERO);
        let (first, nx, cell) = (self.first, self.equations.nx, self.cell);
        let mut rows: Vec<_> = (self.equations.kind.chunks_mut(nx))
            .zip(self.solid_velocity.chunks_mut(nx))
            .enumerate()
            .collect();
        parallel.for_each(&mut rows, |(j, (kinds, velocities))| {
            for (i, (kind, velocity)) in kinds.iter_mut().zip(velocities.iter_mut()).enumerate() {
                let x = cell_center((first, cell), (i, *j));
                let moving = match tank {
                    Some(tank) if !tank.contains(x, 0.0) => Some(Vec2::ZERO),
                    _ => solid(x),
                };
                if let Some(moving) = moving {
                    (*kind, *velocity) = (CellKind::Solid, moving);
                }
            }
        });
    }

    /// Step 2, the particles' volumes: each cell's fill, then fluid (at least half full) or
    /// air.
    fn splat_fill(&mut self, input: &GridInput, parallel: &impl Parallel) {
        let particles = splat_input(input, (self.first, self.cell), &self.equations);
        splat::splat_fill(&particles, &mut self.bands, &mut self.fill, parallel);
        for c in 0..self.equations.len() {
            if self.equations.kind[c] != CellKind::Solid && self.fill[c] >= 0.5 {
                self.equations.kind[c] = CellKind::Fluid;
            }
        }
    }

    /// Step 2 with two liquids: each cell's rest density ratio, the mean of the particles' in
    /// it (one where none is). The equations then read `∇·(∇p/r) = (ρ₀/dt) ∇·u`: a heavier
    /// liquid's pressure rises the faster with depth.
    fn splat_ratios(&mut self, input: &GridInput) {
        let e = &mut self.equations;
        e.ratio.clear();
        if input.ratios.is_empty() {
            return;
        }
        let mut sums = vec![(0.0f32, 0u32); e.len()];
        let origin = self.first.as_vec2();
        for (x, &r) in input.positions.iter().zip(input.ratios) {
            let at = (*x / self.cell - origin).floor();
            if at.x >= 0.0 && at.y >= 0.0 && (at.x as usize) < e.nx && (at.y as usize) < e.ny {
                let sum = &mut sums[at.y as usize * e.nx + at.x as usize];
                *sum = (sum.0 + r, sum.1 + 1);
            }
        }
        e.ratio.extend(
            sums.iter()
                .map(|&(sum, n)| if n > 0 { sum / n as f32 } else { 1.0 }),
        );
    }

    /// Step 3, the particles' `velocities`: each face's, a solid's on its faces.
    fn splat_faces(&mut self, input: &GridInput, velocities: &[Vec2], parallel: &impl Parallel) {
        let (nx, ny) = (self.equations.nx, self.equations.ny);
        let lattices = [(nx + 1, ny), (nx, ny + 1)];
        for (sums, (columns, rows)) in self.face_sums.iter_mut().zip(lattices) {
            sums.clear();
            sums.resize(columns * rows, [0.0; 2]);
        }
        let particles = splat_input(input, (self.first, self.cell), &self.equations);
        let sums = &mut self.face_sums;
        splat::splat_faces(&particles, velocities, &mut self.bands, sums, parallel);
        for axis in 0..2 {
            let faces = &mut self.faces[axis];
            faces.clear();
            faces.extend(self.face_sums[axis].iter().map(|&[sum, weight]| {
                if weight > 0.0 { sum / weight } else { 0.0 }
            }));
            self.close_solid_faces(axis);
        }
    }

    /// Sets every face of a solid cell (and of the rectangle's edge) along `axis` to the
    /// solid's velocity.
    fn close_solid_faces(&mut self, axis: usize) {
        let e = &self.equations;
        let (nx, ny) = (e.nx, e.ny);
        let columns = nx + usize::from(axis == 0);
        for (j, row) in self.faces[axis].chunks_exact_mut(columns).enumerate() {
            for (i, face) in row.iter_mut().enumerate() {
                let (a, b) = face_cells((i, j), axis, (nx, ny));
                let solid = [a, b]
                    .into_iter()
                    .find(|&c| c.is_none_or(|c| e.kind[c] == CellKind::Solid));
                if let Some(c) = solid {
                    *face = c.map_or(0.0, |c| self.solid_velocity[c][axis]);
                }
            }
        }
    }

    /// Step 4's equations: sealed pockets opened, each fluid cell's diagonal (its free-surface
    /// fractions), the unknowns numbered.
    fn assemble_equations(&mut self) {
        let e = &mut self.equations;
        let (reached, stack) = &mut self.scratch;
        e.open_sealed_pockets(reached, stack);
        for c in 0..e.len() {
            if e.kind[c] != CellKind::Fluid {
                continue;
            }
            let mut diag = 0.0;
            for n in e.neighbors(c) {
                diag += match e.kind_of(n) {
                    CellKind::Fluid => e.face(c, n.expect("fluid is inside")),
                    CellKind::Air => {
                        let theta = theta(self.fill[c], self.fill[n.expect("air is inside")]);
                        1.0 / (theta * e.ratio_of(c))
                    }
                    CellKind::Solid => 0.0,
                };
            }
            e.diag[c] = diag * e.off;
        }
        e.number_unknowns();
    }

    /// Step 4's right-hand side: `−(ρ₀/dt) ∇·u` in each fluid cell, for a rest density
    /// `rest_density` and a step of `dt`.
    fn assemble_rhs(&mut self, rest_density: f32, dt: f32) {
        let e = &self.equations;
        let cells = e.len();
        self.rhs.clear();
        self.rhs.resize(cells, 0.0);
        let scale = -f64::from(rest_density / dt);
        for &c in &e.cells {
            let c = c as usize;
            self.rhs[c] = scale * f64::from(divergence(&self.faces, c, (e.nx, e.ny), self.cell));
        }
    }

    /// Step 4's start: the last solve's pressure where the same lattice cell was fluid.
    fn warm_start(&mut self) {
        let e = &self.equations;
        let (first, nx, previous) = (&self.previous.0, self.previous.1, &self.previous.2);
        let rows = previous.len().checked_div(nx).unwrap_or(0);
        self.pressure.clear();
        self.pressure.extend((0..e.len()).map(|c| {
            if !e.is_fluid(c) {
                return 0.0;
            }
            let at = self.first + IVec2::new((c % e.nx) as i32, (c / e.nx) as i32) - *first;
            let inside = at.x >= 0 && at.y >= 0 && (at.x as usize) < nx && (at.y as usize) < rows;
            if inside {
                previous[at.y as usize * nx + at.x as usize]
            } else {
                0.0
            }
        }));
    }

    /// Step 5: the pressure extended past the fluid, for reading back: the fluid cells' own,
    /// and the cells next to them (side by side or corner to corner; farther ones read zero).
    fn extend(&mut self) {
        let mut extended = core::mem::take(&mut self.extended);
        let (mut marked, mut border) = core::mem::take(&mut self.scratch);
        let e = &self.equations;
        extended.clear();
        extended.resize(e.len(), 0.0);
        marked.clear();
        marked.resize(e.len(), false);
        border.clear();
        for &c in &e.cells {
            let c = c as usize;
            extended[c] = self.pressure[c] as f32;
            let at = (c % e.nx, c / e.nx);
            let around = e
                .neighbors_at(c, at)
                .into_iter()
                .chain(e.diagonals_at(c, at));
            for n in around.flatten() {
                if !e.is_fluid(n) && !marked[n] {
                    marked[n] = true;
                    border.push(n);
                }
            }
        }
        for &c in border.iter() {
            let (kind, at) = (e.kind[c], (c % e.nx, c / e.nx));
            // A solid corner cell has no fluid face: it takes its diagonal neighbours' (a
            // particle in the tank's corner reads the floor's pressure, not zero).
            extended[c] = self
                .extend_from(c, kind, e.neighbors_at(c, at))
                .or_else(|| {
                    (kind == CellKind::Solid)
                        .then(|| self.extend_from(c, kind, e.diagonals_at(c, at)))
                        .flatten()
                })
                .unwrap_or(0.0);
        }
        self.extended = extended;
        self.scratch = (marked, border);
    }
}

impl GridPressure {
    /// The extended pressure of a `kind` cell `c` (not fluid) from its fluid cells among
    /// `neighbors`, averaged: hydrostatically into a solid, along the ghost-fluid line through
    /// zero at the surface into air; `None` without a fluid one.
    fn extend_from(&self, c: usize, kind: CellKind, neighbors: [Option<usize>; 4]) -> Option<f32> {
        let e = &self.equations;
        let (mut sum, mut count) = (0.0, 0);
        for n in neighbors.into_iter().flatten().filter(|&n| e.is_fluid(n)) {
            let p = self.pressure[n] as f32;
            sum += if kind == CellKind::Solid {
                p + e.ratio_of(n) * self.weight.dot(self.center(c) - self.center(n))
            } else {
                p * (1.0 - 1.0 / theta(self.fill[n], self.fill[c]))
            };
            count += 1;
        }
        (count > 0).then(|| sum / count as f32)
    }
}

/// Where the free surface lies between a fluid cell and an air one, as a fraction of the way
/// from the fluid cell's centre (the zero of `½ − fill`, linearly between them).
fn theta(fluid_fill: f32, air_fill: f32) -> f32 {
    let (inside, outside) = (fluid_fill - 0.5, 0.5 - air_fill);
    (inside / (inside + outside)).clamp(MIN_THETA, 1.0)
}

/// The two cells on either side of face `(i, j)` normal to `axis` (lower, upper), `None` off
/// the rectangle.
fn face_cells(
    (i, j): (usize, usize),
    axis: usize,
    (nx, ny): (usize, usize),
) -> (Option<usize>, Option<usize>) {
    let upper = (i < nx && j < ny).then(|| j * nx + i);
    let lower = if axis == 0 {
        (i > 0 && j < ny).then(|| j * nx + i - 1)
    } else {
        (j > 0 && i < nx).then(|| (j - 1) * nx + i)
    };
    (lower, upper)
}

/// What the splat reads of `input`'s particles and of the rectangle from lattice index `first`
/// of cells of side `cell` and kinds `equations.kind`.
fn splat_input<'a>(
    input: &GridInput<'a>,
    (first, cell): (IVec2, f32),
    equations: &'a Laplacian,
) -> SplatInput<'a> {
    SplatInput {
        positions: input.positions,
        cell,
        origin: first.as_vec2(),
        size: (equations.nx, equations.ny),
        kind: &equations.kind,
        share: input.spacing * input.spacing / (cell * cell),
    }
}

/// `∇·u` of cell `c` from its four faces, 1/s.
fn divergence(faces: &[Vec<f32>; 2], c: usize, (nx, _ny): (usize, usize), cell: f32) -> f32 {
    let (i, j) = (c % nx, c / nx);
    let u = &faces[0][j * (nx + 1) + i..];
    let (v_low, v_high) = (faces[1][j * nx + i], faces[1][(j + 1) * nx + i]);
    (u[1] - u[0] + v_high - v_low) / cell
}

/// The centre of cell `(i, j)` of a rectangle from lattice index `first`, of cells of side
/// `cell`, m.
#[inline]
fn cell_center((first, cell): (IVec2, f32), (i, j): (usize, usize)) -> Vec2 {
    let index = first + IVec2::new(i as i32, j as i32);
    (index.as_vec2() + Vec2::splat(0.5)) * cell
}

/// The side of the cells, m: `nominal`, stretched or shrunk to fit a whole number of cells
/// across the tank's width, if any, so that both side walls (as the floor, on the lattice's
/// origin) lie on cell faces. A wall through the middle of a cell moved the solid boundary by
/// up to half a cell on one side: in a layer at rest against it the particles circulated at
/// 16% of `√(gD)`.
fn cell_size(nominal: f32, tank: Option<Tank>) -> f32 {
    match tank {
        Some(tank) if nominal > 0.0 && tank.size().x > nominal => {
            tank.size().x / (tank.size().x / nominal).round()
        }
        _ => nominal,
    }
}

#[cfg(test)]
mod tests;
