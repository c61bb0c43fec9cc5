//! The preconditioner of the grid's conjugate gradient: one multigrid V-cycle (McAdams,
//! Sifakis & Teran, "A parallel multigrid Poisson solver for fluids simulation on large
//! grids", SCA 2010), in f32. Coarse levels rediscretise the equations on cells of twice the
//! size ([`Laplacian::coarsen_into`]); the transfers are cell-centred bilinear interpolation and its
//! transpose, a weight that would read a solid coarse cell read from the cell's own parent
//! instead (the closed wall's mirror); the smoother is damped Jacobi, the same number of sweeps
//! before and after, so the cycle is a symmetric operator, as conjugate gradients needs.

use super::laplacian::{CellKind, Laplacian};
use crate::sim::parallel::{Parallel, for_each_slot};

/// Jacobi sweeps before and after the coarse correction.
const SWEEPS: usize = 2;

/// Jacobi sweeps on the coarsest level.
const COARSEST_SWEEPS: usize = 32;

/// The Jacobi damping (4/5 smooths the five-point Laplacian best).
const DAMPING: f32 = 0.8;

/// Levels stop coarsening at this many cells a side (or at [`MAX_LEVELS`]).
const COARSEST_SIDE: usize = 4;

/// At most this many levels.
const MAX_LEVELS: usize = 16;

/// An interpolation weight from a coarse cell.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Weight {
    coarse: u32,
    weight: f32,
}

/// One level: its equations, its right-hand side and solution over its unknowns (each with
/// the zero slot last), and (below the finest) how the level above reads it.
#[derive(Debug, Clone, Default)]
struct Level {
    equations: Laplacian,
    b: Vec<f32>,
    x: Vec<f32>,
    scratch: Vec<f32>,
    /// For every unknown of the level above, the (up to four) unknowns of this level it
    /// interpolates from (weight zero on this level's zero slot where there are fewer).
    reads: Vec<[Weight; 4]>,
}

/// A V-cycle over the levels of a grid's equations.
#[derive(Debug, Clone, Default)]
pub(crate) struct Multigrid {
    levels: Vec<Level>,
}

impl Multigrid {
    /// Builds the levels below `fine` (whose own diagonal, free surface fractions included, the
    /// finest level keeps), reusing the last levels' storage.
    pub fn rebuild(&mut self, fine: &Laplacian) {
        let mut depth = 1;
        if self.levels.is_empty() {
            self.levels.push(Level::default());
        }
        self.levels[0].equations.clone_from(fine);
        while depth < MAX_LEVELS {
            let above = &self.levels[depth - 1].equations;
            if above.nx <= COARSEST_SIDE && above.ny <= COARSEST_SIDE {
                break;
            }
            if self.levels.len() == depth {
                self.levels.push(Level::default());
            }
            let (upper, lower) = self.levels.split_at_mut(depth);
            let (above, level) = (&upper[depth - 1].equations, &mut lower[0]);
            above.coarsen_into(&mut level.equations);
            interpolation(above, &level.equations, &mut level.reads);
            depth += 1;
        }
        self.levels.truncate(depth);
        for level in &mut self.levels {
            let n = level.equations.unknowns() + 1;
            for v in [&mut level.b, &mut level.x, &mut level.scratch] {
                v.clear();
                v.resize(n, 0.0);
            }
        }
    }

    /// Number of levels.
    pub fn depth(&self) -> usize {
        self.levels.len()
    }

    /// `z ≈ A⁻¹ r` by one V-cycle from zero (`z` and `r` over the finest level's unknowns).
    pub fn apply(&mut self, r: &[f64], z: &mut [f64], parallel: &impl Parallel) {
        let top = &mut self.levels[0];
        let n = top.equations.unknowns();
        for (b, r) in top.b[..n].iter_mut().zip(r) {
            *b = *r as f32;
        }
        cycle(&mut self.levels, parallel);
        for (z, x) in z[..n].iter_mut().zip(&self.levels[0].x) {
            *z = f64::from(*x);
        }
    }
}

/// One V-cycle on `levels[0]` (its `b` to its `x`), recursively.
fn cycle(levels: &mut [Level], parallel: &impl Parallel) {
    let (level, coarser) = levels.split_first_mut().expect("at least one level");
    level.x.fill(0.0);
    let Some(coarse) = coarser.first_mut() else {
        smooth(level, COARSEST_SWEEPS, parallel);
        return;
    };
    smooth(level, SWEEPS, parallel);
    restrict_residual(level, coarse, parallel);
    cycle(coarser, parallel);
    let coarse = &coarser[0];
    let n = level.equations.unknowns();
    for_each_slot(&mut level.x[..n], parallel, |k, x| {
        *x += coarse.reads[k]
            .iter()
            .map(|w| w.weight * coarse.x[w.coarse as usize])
            .sum::<f32>();
        0.0
    });
    smooth(level, SWEEPS, parallel);
}

/// `sweeps` damped Jacobi sweeps of `level.x` towards `A x = b`.
fn smooth(level: &mut Level, sweeps: usize, parallel: &impl Parallel) {
    let n = level.equations.unknowns();
    for _ in 0..sweeps {
        let (equations, b, x) = (&level.equations, &level.b, &level.x);
        for_each_slot(&mut level.scratch[..n], parallel, |k, out| {
            *out = x[k] + DAMPING * (b[k] - equations.apply_f32(k, x)) / equations.unknown_diag[k];
            0.0
        });
        core::mem::swap(&mut level.x, &mut level.scratch);
    }
}

/// The coarse right-hand side: the residual of `level`, restricted by the transpose of the
/// interpolation over four (the average of a cell's children on smooth fields).
fn restrict_residual(level: &mut Level, coarse: &mut Level, parallel: &impl Parallel) {
    let n = level.equations.unknowns();
    let (equations, b, x) = (&level.equations, &level.b, &level.x);
    for_each_slot(&mut level.scratch[..n], parallel, |k, r| {
        *r = b[k] - equations.apply_f32(k, x);
        0.0
    });
    coarse.b.fill(0.0);
    for (reads, &r) in coarse.reads.iter().zip(&level.scratch[..n]) {
        for w in reads.iter().filter(|w| w.weight != 0.0) {
            coarse.b[w.coarse as usize] += 0.25 * w.weight * r;
        }
    }
}

/// For every unknown of `fine`, the unknowns of `coarse` it reads (into `reads`): bilinear
/// between the centres of its parent and the parent's neighbours on its side (9, 3, 3 and 1
/// sixteenths), the weight of a solid neighbour moved to the parent, an air one's dropped (zero
/// pressure).
fn interpolation(fine: &Laplacian, coarse: &Laplacian, reads: &mut Vec<[Weight; 4]>) {
    let none = Weight {
        coarse: coarse.unknowns() as u32,
        weight: 0.0,
    };
    let unknown = |c: usize| coarse.unknown[c];
    reads.clear();
    reads.extend(fine.cells.iter().map(|&c| {
        let c = c as usize;
        let mut weights = [none; 4];
        let (i, j) = ((c % fine.nx) as isize, (c / fine.nx) as isize);
        let (pi, pj) = (i / 2, j / 2);
        let (si, sj) = (
            if i % 2 == 0 { -1 } else { 1 },
            if j % 2 == 0 { -1 } else { 1 },
        );
        let at = |di: isize, dj: isize| {
            let (ci, cj) = (pi + di, pj + dj);
            let inside = ci >= 0 && cj >= 0 && (ci as usize) < coarse.nx;
            let inside = inside && (cj as usize) < coarse.ny;
            inside.then(|| cj as usize * coarse.nx + ci as usize)
        };
        let parent = at(0, 0).expect("a fine cell's parent is on the coarse level");
        let mut parent_weight = 9.0 / 16.0;
        for (k, (di, dj, weight)) in [(si, 0, 3.0), (0, sj, 3.0), (si, sj, 1.0)]
            .into_iter()
            .enumerate()
        {
            let n = at(di, dj);
            match coarse.kind_of(n) {
                CellKind::Fluid => {
                    weights[k + 1] = Weight {
                        coarse: unknown(n.expect("fluid is inside")),
                        weight: weight / 16.0,
                    }
                }
                CellKind::Solid => parent_weight += weight / 16.0,
                CellKind::Air => {}
            }
        }
        if coarse.is_fluid(parent) {
            weights[0] = Weight {
                coarse: unknown(parent),
                weight: parent_weight,
            };
        }
        weights
    }));
}
