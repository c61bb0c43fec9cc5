//! The preconditioner of the grid's conjugate gradient: one multigrid V-cycle (McAdams,
//! Sifakis & Teran, "A parallel multigrid Poisson solver for fluids simulation on large
//! grids", SCA 2010), in f32. Coarse levels rediscretise the equations on cells of twice the
//! size ([`Laplacian::coarsen`]); the transfers are cell-centred bilinear interpolation and its
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

/// One level: its equations, its right-hand side and solution, and (below the finest) how
/// the level above reads it.
#[derive(Debug, Clone, Default)]
struct Level {
    equations: Laplacian,
    b: Vec<f32>,
    x: Vec<f32>,
    scratch: Vec<f32>,
    /// For every cell of the level above, the (up to four) coarse cells it interpolates from.
    reads: Vec<[Weight; 4]>,
}

/// A V-cycle over the levels of a grid's equations.
#[derive(Debug, Clone, Default)]
pub(crate) struct Multigrid {
    levels: Vec<Level>,
}

impl Multigrid {
    /// Builds the levels below `fine` (whose own diagonal, free surface fractions included, the
    /// finest level keeps).
    pub fn rebuild(&mut self, fine: &Laplacian) {
        let mut levels = core::mem::take(&mut self.levels);
        levels.truncate(1);
        levels.resize_with(1, Level::default);
        levels[0].equations.clone_from(fine);
        while levels.len() < MAX_LEVELS {
            let above = &levels[levels.len() - 1].equations;
            if above.nx <= COARSEST_SIDE && above.ny <= COARSEST_SIDE {
                break;
            }
            let equations = above.coarsen();
            let reads = interpolation(above, &equations);
            levels.push(Level {
                equations,
                reads,
                ..Level::default()
            });
        }
        for level in &mut levels {
            let n = level.equations.len();
            for v in [&mut level.b, &mut level.x, &mut level.scratch] {
                v.clear();
                v.resize(n, 0.0);
            }
        }
        self.levels = levels;
    }

    /// Number of levels.
    pub fn depth(&self) -> usize {
        self.levels.len()
    }

    /// `z ≈ A⁻¹ r` by one V-cycle from zero (`z` and `r` over the finest level's cells).
    pub fn apply(&mut self, r: &[f64], z: &mut [f64], parallel: &impl Parallel) {
        let top = &mut self.levels[0];
        for (b, r) in top.b.iter_mut().zip(r) {
            *b = *r as f32;
        }
        cycle(&mut self.levels, parallel);
        for (z, x) in z.iter_mut().zip(&self.levels[0].x) {
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
    restrict_residual(level, coarse);
    cycle(coarser, parallel);
    let coarse = &coarser[0];
    let (x, equations) = (&mut level.x, &level.equations);
    for_each_slot(x, parallel, |c, x| {
        if equations.is_fluid(c) {
            *x += coarse.reads[c]
                .iter()
                .map(|w| w.weight * coarse.x[w.coarse as usize])
                .sum::<f32>();
        }
        0.0
    });
    smooth(level, SWEEPS, parallel);
}

/// `sweeps` damped Jacobi sweeps of `level.x` towards `A x = b`.
fn smooth(level: &mut Level, sweeps: usize, parallel: &impl Parallel) {
    for _ in 0..sweeps {
        let (equations, b, x) = (&level.equations, &level.b, &level.x);
        for_each_slot(&mut level.scratch, parallel, |c, out| {
            *out = if equations.is_fluid(c) {
                x[c] + DAMPING * (b[c] - equations.apply_f32(c, x)) / equations.diag[c]
            } else {
                0.0
            };
            0.0
        });
        core::mem::swap(&mut level.x, &mut level.scratch);
    }
}

/// The coarse right-hand side: the residual of `level`, restricted by the transpose of the
/// interpolation over four (the average of a cell's children on smooth fields).
fn restrict_residual(level: &mut Level, coarse: &mut Level) {
    let (equations, b, x) = (&level.equations, &level.b, &level.x);
    coarse.b.fill(0.0);
    for (c, &bc) in b.iter().enumerate() {
        if !equations.is_fluid(c) {
            continue;
        }
        let r = bc - equations.apply_f32(c, x);
        for w in &coarse.reads[c] {
            coarse.b[w.coarse as usize] += 0.25 * w.weight * r;
        }
    }
}

/// For every fluid cell of `fine`, the coarse cells it reads: bilinear between the centres of
/// its parent and the parent's neighbours on its side (9, 3, 3 and 1 sixteenths), the weight of
/// a solid neighbour moved to the parent, an air one's dropped (zero pressure).
fn interpolation(fine: &Laplacian, coarse: &Laplacian) -> Vec<[Weight; 4]> {
    (0..fine.len())
        .map(|c| {
            let mut reads = [Weight::default(); 4];
            if !fine.is_fluid(c) {
                return reads;
            }
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
                        reads[k + 1] = Weight {
                            coarse: n.expect("fluid is inside") as u32,
                            weight: weight / 16.0,
                        }
                    }
                    CellKind::Solid => parent_weight += weight / 16.0,
                    CellKind::Air => {}
                }
            }
            if coarse.is_fluid(parent) {
                reads[0] = Weight {
                    coarse: parent as u32,
                    weight: parent_weight,
                };
            }
            reads
        })
        .collect()
}
