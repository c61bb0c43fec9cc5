//! Conjugate gradients on the grid's pressure equations, preconditioned by a multigrid V-cycle
//! ([`Multigrid`]), in f64; every sum in chunks of fixed size, so the iterations (and the
//! pressure) are the same on any number of threads.

use super::laplacian::Laplacian;
use super::multigrid::Multigrid;
use crate::sim::parallel::{Parallel, Sequential, for_each_slot};

/// Fewest unknowns whose passes run in parallel. A V-cycle is some forty passes of a few
/// nanoseconds an unknown: at 2,427 unknowns (the demo's dam break at 10,000 particles) handing
/// each to the other thread made the solve 1.3 times slower than running it on one.
pub(crate) const PARALLEL_UNKNOWNS: usize = 8192;

/// The vectors of a solve over the unknowns (each with the zero slot last), kept between
/// solves.
#[derive(Debug, Clone, Default)]
pub(crate) struct Pcg {
    b: Vec<f64>,
    x: Vec<f64>,
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
    /// Solves `A x = b` (both over the rectangle's cells) from the `x` given, until the largest
    /// residual is at most `tolerance` times the largest `|b|` (or `max_iterations`); `x` is
    /// written on the fluid cells only.
    pub fn solve(
        &mut self,
        (a, mg): (&Laplacian, &mut Multigrid),
        b: &[f64],
        x: &mut [f64],
        (tolerance, max_iterations): (f64, u32),
        parallel: &impl Parallel,
    ) -> PcgResult {
        let n = a.unknowns();
        for v in [&mut self.r, &mut self.z, &mut self.d, &mut self.q] {
            v.clear();
            v.resize(n + 1, 0.0);
        }
        for (v, from) in [(&mut self.b, b), (&mut self.x, &*x)] {
            v.clear();
            v.extend(a.cells.iter().map(|&c| from[c as usize]));
            v.push(0.0);
        }
        let limits = (tolerance, max_iterations);
        let result = if n < PARALLEL_UNKNOWNS {
            self.iterate((a, mg), limits, &Sequential)
        } else {
            self.iterate((a, mg), limits, parallel)
        };
        for (&c, &value) in a.cells.iter().zip(&self.x) {
            x[c as usize] = value;
        }
        result
    }

    /// The conjugate gradients on the gathered `b` and `x`.
    fn iterate(
        &mut self,
        (a, mg): (&Laplacian, &mut Multigrid),
        (tolerance, max_iterations): (f64, u32),
        parallel: &impl Parallel,
    ) -> PcgResult {
        let n = a.unknowns();
        let b_max = self.b.iter().fold(0.0f64, |m, b| m.max(b.abs()));
        let (b, x) = (&self.b, &self.x);
        let mut r_max = fold_max(&mut self.r[..n], parallel, |k, r| {
            *r = b[k] - a.apply_f64(k, x);
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
            let dq = for_each_slot(&mut self.q[..n], parallel, |k, q| {
                *q = a.apply_f64(k, d);
                *q * d[k]
            });
            if dq <= 0.0 {
                break;
            }
            let alpha = rz / dq;
            for (x, d) in self.x.iter_mut().zip(d) {
                *x += alpha * d;
            }
            let q = &self.q;
            r_max = fold_max(&mut self.r[..n], parallel, |k, r| {
                *r -= alpha * q[k];
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
