//! Conjugate gradients on the grid's pressure equations, preconditioned by a multigrid V-cycle
//! ([`Multigrid`]), in f64; every sum in chunks of fixed size, so the iterations (and the
//! pressure) are the same on any number of threads.

use super::laplacian::Laplacian;
use super::multigrid::Multigrid;
use crate::sim::parallel::{Parallel, for_each_slot};

/// The vectors of a solve, kept between solves.
#[derive(Debug, Clone, Default)]
pub(crate) struct Pcg {
    r: Vec<f64>,
    z: Vec<f64>,
    d: Vec<f64>,
    q: Vec<f64>,
}

/// What a solve did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct PcgResult {
    /// Iterations (V-cycles) taken.
    pub iterations: u32,
    /// The largest residual left over the largest right-hand side.
    pub relative_residual: f64,
}

impl Pcg {
    /// Solves `A x = b` from the `x` given (zero off the fluid), until the largest residual is at most `tolerance`
    /// times the largest `|b|` (or `max_iterations`).
    pub fn solve(
        &mut self,
        (a, mg): (&Laplacian, &mut Multigrid),
        b: &[f64],
        x: &mut [f64],
        (tolerance, max_iterations): (f64, u32),
        parallel: &impl Parallel,
    ) -> PcgResult {
        let n = a.len();
        for v in [&mut self.r, &mut self.z, &mut self.d, &mut self.q] {
            v.clear();
            v.resize(n, 0.0);
        }
        debug_assert!(
            (0..n).all(|c| a.is_fluid(c) || x[c] == 0.0),
            "the start is zero off the fluid"
        );
        let b_max = b.iter().fold(0.0f64, |m, b| m.max(b.abs()));
        let x_in = &*x;
        let mut r_max = fold_max(&mut self.r, parallel, |c, r| {
            *r = if a.is_fluid(c) {
                b[c] - a.apply_f64(c, x_in)
            } else {
                0.0
            };
            *r
        });
        let goal = tolerance * b_max;
        let mut iterations = 0;
        if b_max == 0.0 || r_max <= goal {
            return result(iterations, r_max, b_max);
        }
        mg.apply(&self.r, &mut self.z, parallel);
        self.d.copy_from_slice(&self.z);
        let mut rz = dot(&self.r, &self.z);
        while iterations < max_iterations {
            iterations += 1;
            let d = &self.d;
            let dq = for_each_slot(&mut self.q, parallel, |c, q| {
                *q = a.apply_f64(c, d);
                *q * d[c]
            });
            if dq <= 0.0 {
                break;
            }
            let alpha = rz / dq;
            for (x, d) in x.iter_mut().zip(d) {
                *x += alpha * d;
            }
            let q = &self.q;
            r_max = fold_max(&mut self.r, parallel, |c, r| {
                *r -= alpha * q[c];
                *r
            });
            if r_max <= goal {
                break;
            }
            mg.apply(&self.r, &mut self.z, parallel);
            let rz_next = dot(&self.r, &self.z);
            let beta = rz_next / rz;
            rz = rz_next;
            for (d, z) in self.d.iter_mut().zip(&self.z) {
                *d = z + beta * *d;
            }
        }
        result(iterations, r_max, b_max)
    }
}

fn result(iterations: u32, r_max: f64, b_max: f64) -> PcgResult {
    PcgResult {
        iterations,
        relative_residual: if b_max > 0.0 { r_max / b_max } else { 0.0 },
    }
}

/// `Σ a·b`, in cell order.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}

/// Writes `work(c, &mut out[c])` for every cell and returns the largest `|value|` it returns.
fn fold_max(
    out: &mut [f64],
    parallel: &impl Parallel,
    work: impl Fn(usize, &mut f64) -> f64 + Sync,
) -> f64 {
    crate::sim::parallel::fold_slots(out, parallel, |c, v| work(c, v).abs(), f64::max)
}
