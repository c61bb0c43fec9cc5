//! Steps 2 and 3 of a solve, the particles onto the grid: each cell's fill ([`splat_fill`],
//! from the positions alone) and each face's weighted velocity ([`splat_faces`]), splatted
//! bilinearly, in parallel bands.
//!
//! The particles are split into runs of consecutive indices, a fixed number of them whatever the
//! thread count ([`BANDS`]); each run is splatted into arrays of its own covering just the
//! lattice rows its particles touch (a run of the cell-sorted particles covers a few rows), and
//! the runs' arrays are then added into the grid's in run order. So the sums are the same on any
//! number of threads, and the threads share no cell.

use super::CellKind;
use crate::sim::parallel::{Parallel, chunk_size};
use bevy::math::Vec2;
use core::ops::Range;

/// Runs the particles are split into (at least [`BAND_PARTICLES`] each).
const BANDS: usize = 8;

/// Fewest particles in a run of the splat.
const BAND_PARTICLES: usize = 256;

/// What the splat reads: the particles and the grid's rectangle.
#[derive(Debug, Clone, Copy)]
pub(super) struct SplatInput<'a> {
    /// Particle positions, m.
    pub positions: &'a [Vec2],
    /// A cell's side, m.
    pub cell: f32,
    /// The lattice index of the rectangle's first cell.
    pub origin: Vec2,
    /// The rectangle's cells across and up.
    pub size: (usize, usize),
    /// The cells' kinds, row by row: [`splat_fill`] keeps a particle's volume off the solid
    /// ones (the face pass reads none).
    pub kind: &'a [CellKind],
    /// A particle's volume as a share of a cell.
    pub share: f32,
}

/// The fill and face sums of one run of particles over the lattice rows it touches.
#[derive(Debug, Clone, Default)]
pub(super) struct Band {
    particles: Range<usize>,
    /// The first lattice row the run touches.
    first_row: usize,
    /// The lattice rows of faces normal to y the run touches from `first_row` on (cells and
    /// faces normal to x: as many, within the rectangle).
    rows: usize,
    /// The cells' fill, from `first_row` on.
    fill: Vec<f32>,
    /// Each face's weighted velocity sum and weight (normal to x, then to y), from `first_row`
    /// on.
    face_sums: [Vec<[f32; 2]>; 2],
}

/// The cells' fill of `input`'s particles, added into `fill` (which comes in zeroed): every
/// particle at a finite position counts, whatever its velocity (the face pass skips one whose
/// velocity is not finite). `bands` keeps the runs' arrays from solve to solve, and the rows
/// each run touches for [`splat_faces`] with the same particles.
pub(super) fn splat_fill(
    input: &SplatInput,
    bands: &mut Vec<Band>,
    fill: &mut [f32],
    parallel: &impl Parallel,
) {
    let len = input.positions.len();
    let size = chunk_size(len, BANDS, BAND_PARTICLES);
    bands.resize_with(len.div_ceil(size), Band::default);
    for (k, band) in bands.iter_mut().enumerate() {
        band.particles = k * size..((k + 1) * size).min(len);
    }
    parallel.for_each(bands, |band| band.splat_fill(input));
    let nx = input.size.0;
    for band in bands.iter() {
        add_rows(fill, &band.fill, band.first_row * nx, |w, p| *w += p);
    }
}

/// The faces' weighted velocity sums of the particles [`splat_fill`] splatted, with
/// `velocities`, added into `face_sums` (faces normal to x, `(nx + 1) ny`, then to y,
/// `nx (ny + 1)`, which come in zeroed).
pub(super) fn splat_faces(
    input: &SplatInput,
    velocities: &[Vec2],
    bands: &mut [Band],
    face_sums: &mut [Vec<[f32; 2]>; 2],
    parallel: &impl Parallel,
) {
    parallel.for_each(bands, |band| band.splat_faces(input, velocities));
    let nx = input.size.0;
    for band in bands.iter() {
        for (axis, sums) in face_sums.iter_mut().enumerate() {
            let columns = nx + usize::from(axis == 0);
            let part = &band.face_sums[axis];
            add_rows(sums, part, band.first_row * columns, |w, p| {
                w[0] += p[0];
                w[1] += p[1];
            });
        }
    }
}

/// Adds `part` into `whole` from index `start` on, element by element with `add`.
fn add_rows<T: Copy>(whole: &mut [T], part: &[T], start: usize, add: impl Fn(&mut T, T)) {
    for (w, &p) in whole[start..].iter_mut().zip(part) {
        add(w, p);
    }
}

impl Band {
    /// Finds the rows the run touches and splats its particles' volumes into the band's fill.
    fn splat_fill(&mut self, input: &SplatInput) {
        let (nx, ny) = input.size;
        let positions = &input.positions[self.particles.clone()];
        // The rows touched: from the cell centres' lattice below the lowest particle to the
        // faces' above the highest.
        let (mut low, mut high) = (f32::MAX, f32::MIN);
        for x in positions.iter().filter(|x| x.is_finite()) {
            let y = input.lattice(*x).y;
            (low, high) = (low.min(y), high.max(y));
        }
        let first = (low - 0.5).floor().clamp(0.0, ny as f32 - 1.0);
        let last = (high.floor() + 1.0).clamp(first, ny as f32);
        self.first_row = if low <= high { first as usize } else { 0 };
        self.rows = if low <= high {
            last as usize - self.first_row + 1
        } else {
            0
        };
        let cell_rows = self.cell_rows(ny);
        self.fill.clear();
        self.fill.resize(nx * cell_rows, 0.0);
        if self.rows == 0 {
            return;
        }
        let kind = &input.kind[self.first_row * nx..];
        let offset = Vec2::new(0.0, self.first_row as f32);
        for &x in positions.iter().filter(|x| x.is_finite()) {
            let g = input.lattice(x) - offset;
            spread_volume(&mut self.fill, kind, (nx, cell_rows), g, input.share);
        }
    }

    /// Splats the run's particles' `velocities` into the band's face sums, over the rows
    /// [`splat_fill`](Self::splat_fill) found.
    fn splat_faces(&mut self, input: &SplatInput, velocities: &[Vec2]) {
        let (nx, ny) = input.size;
        let run = self.particles.clone();
        let (positions, velocities) = (&input.positions[run.clone()], &velocities[run]);
        // Cells and faces normal to x have `ny` rows, faces normal to y `ny + 1`.
        let lattices = [(nx + 1, self.cell_rows(ny)), (nx, self.rows)];
        for (sums, (columns, rows)) in self.face_sums.iter_mut().zip(lattices) {
            sums.clear();
            sums.resize(columns * rows, [0.0; 2]);
        }
        if self.rows == 0 {
            return;
        }
        let offset = Vec2::new(0.0, self.first_row as f32);
        for (&x, &v) in positions.iter().zip(velocities) {
            if !(x.is_finite() && v.is_finite()) {
                continue;
            }
            let g = input.lattice(x) - offset;
            if !self.faces_inside(g, v, input, lattices) {
                for (axis, sums) in self.face_sums.iter_mut().enumerate() {
                    // Faces normal to x lie half a cell up from the lattice points, those
                    // normal to y half a cell right.
                    let half = if axis == 0 { Vec2::Y } else { Vec2::X } * 0.5;
                    bilinear(g - half, lattices[axis], |f, w| {
                        sums[f][0] += w * v[axis];
                        sums[f][1] += w;
                    });
                }
            }
        }
    }

    /// The rows of cells (and faces normal to x) the run touches, within the rectangle's `ny`.
    fn cell_rows(&self, ny: usize) -> usize {
        self.rows.min(ny - self.first_row.min(ny))
    }

    /// The face sums of one particle at lattice point `g` (the band's rows) with velocity `v`
    /// where all its faces lie on the band's `lattices` (faces normal to x, then to y), the
    /// common case, in straight-line code; `false` (and nothing done) otherwise.
    #[inline]
    fn faces_inside(
        &mut self,
        g: Vec2,
        v: Vec2,
        input: &SplatInput,
        lattices: [(usize, usize); 2],
    ) -> bool {
        let nx = input.size.0;
        // The lattice points below and left of `g` (faces) and of `g − ½` (cell centres).
        let (point, centre) = (floor(g), floor(g - Vec2::splat(0.5)));
        let inside = centre.x >= 0.0
            && centre.y >= 0.0
            && point.x + 1.0 < lattices[0].0 as f32
            && centre.y + 1.0 < lattices[0].1 as f32
            && centre.x + 1.0 < lattices[1].0 as f32
            && point.y + 1.0 < lattices[1].1 as f32;
        if !inside {
            return false;
        }
        let (f, h) = (g - point, g - Vec2::splat(0.5) - centre);
        let (i, j) = (point.x as usize, point.y as usize);
        let (ci, cj) = (centre.x as usize, centre.y as usize);
        // Side by side along a row, two faces' sums and weights are added at once. Faces normal
        // to x: columns at the lattice points, rows at the centres'.
        let u = cj * (nx + 1) + i;
        let sums = self.face_sums[0].as_flattened_mut();
        let [w00, w10, w01, w11] = weights(f, h);
        add_at(sums, 2 * u, [w00 * v.x, w00, w10 * v.x, w10]);
        add_at(sums, 2 * (u + nx + 1), [w01 * v.x, w01, w11 * v.x, w11]);
        // Faces normal to y: columns at the centres', rows at the lattice points.
        let u = j * nx + ci;
        let sums = self.face_sums[1].as_flattened_mut();
        let [w00, w10, w01, w11] = weights(h, f);
        add_at(sums, 2 * u, [w00 * v.y, w00, w10 * v.y, w10]);
        add_at(sums, 2 * (u + nx), [w01 * v.y, w01, w11 * v.y, w11]);
        true
    }
}

impl SplatInput<'_> {
    /// `x` in lattice coordinates of the rectangle: cells from its first.
    #[inline]
    fn lattice(&self, x: Vec2) -> Vec2 {
        x / self.cell - self.origin
    }
}

/// The bilinear weights of the four points about a lattice point (that point, right, up,
/// up-right), the fractions across from `a.x` and up from `b.y`.
#[inline]
fn weights(a: Vec2, b: Vec2) -> [f32; 4] {
    [
        (1.0 - a.x) * (1.0 - b.y),
        a.x * (1.0 - b.y),
        (1.0 - a.x) * b.y,
        a.x * b.y,
    ]
}

/// Adds `add` to the `N` values from `at` on.
#[inline]
fn add_at<const N: usize>(values: &mut [f32], at: usize, add: [f32; N]) {
    let values: &mut [f32; N] = (&mut values[at..at + N])
        .try_into()
        .expect("a range of N values");
    for (value, add) in values.iter_mut().zip(add) {
        *value += add;
    }
}

/// Adds a particle's volume (`share` of a cell) at lattice point `g` to the cells about it, in a
/// `nx` × `ny` rectangle of cells of `kind`; what falls on a solid cell or off the rectangle
/// stays in the particle's own cell.
fn spread_volume(
    fill: &mut [f32],
    kind: &[CellKind],
    (nx, ny): (usize, usize),
    g: Vec2,
    share: f32,
) {
    if let Some((c, weights)) = stencil(g - Vec2::splat(0.5), (nx, ny)) {
        // All four cells on the grid: the particle's own is one of them.
        let cells = [c, c + 1, c + nx, c + nx + 1];
        let mut kept = 0.0;
        for (&c, w) in cells.iter().zip(weights) {
            if kind[c] == CellKind::Solid {
                kept += w * share;
            } else {
                fill[c] += w * share;
            }
        }
        if kept > 0.0 {
            let own = floor(g);
            let own = own.y as usize * nx + own.x as usize;
            if kind[own] != CellKind::Solid {
                fill[own] += kept;
            }
        }
        return;
    }
    let own = floor(g);
    let own = (own.x >= 0.0 && own.y >= 0.0 && own.x < nx as f32 && own.y < ny as f32)
        .then(|| own.y as usize * nx + own.x as usize)
        .filter(|&c| kind[c] != CellKind::Solid);
    let mut kept = 0.0;
    bilinear_all(g - Vec2::splat(0.5), (nx, ny), |c, w| match c {
        Some(c) if kind[c] != CellKind::Solid => fill[c] += w * share,
        _ => kept += w * share,
    });
    if let Some(own) = own {
        fill[own] += kept;
    }
}

/// `g.floor()` for coordinates under 2³¹ in size, in two conversions: `f32::floor` is a library
/// call on targets without SSE4.1, and the splat takes three of these per particle.
#[inline]
pub(super) fn floor(g: Vec2) -> Vec2 {
    let truncated = g.as_ivec2().as_vec2();
    truncated - Vec2::select(truncated.cmpgt(g), Vec2::ONE, Vec2::ZERO)
}

/// Calls `add(index, weight)` for the (up to four) points of a `columns` × `rows` lattice about
/// `g` (lattice coordinates) that lie on it, with their bilinear weights.
fn bilinear(g: Vec2, (columns, rows): (usize, usize), mut add: impl FnMut(usize, f32)) {
    if let Some((c, weights)) = stencil(g, (columns, rows)) {
        for (c, w) in [c, c + 1, c + columns, c + columns + 1]
            .into_iter()
            .zip(weights)
        {
            add(c, w);
        }
        return;
    }
    bilinear_all(g, (columns, rows), |c, w| {
        if let Some(c) = c {
            add(c, w)
        }
    });
}

/// The first of the four points of a `columns` × `rows` lattice about `g` (lattice
/// coordinates) and their bilinear weights (that point, right, up, up-right), if all four lie
/// on it.
#[inline]
fn stencil(g: Vec2, (columns, rows): (usize, usize)) -> Option<(usize, [f32; 4])> {
    let base = floor(g);
    let on = base.x >= 0.0
        && base.y >= 0.0
        && base.x + 1.0 < columns as f32
        && base.y + 1.0 < rows as f32;
    if !on {
        return None;
    }
    let f = g - base;
    let c = base.y as usize * columns + base.x as usize;
    Some((c, weights(f, f)))
}

/// [`bilinear`] over all four points, `None` for those off the lattice.
fn bilinear_all(g: Vec2, (columns, rows): (usize, usize), mut add: impl FnMut(Option<usize>, f32)) {
    let base = floor(g);
    let f = g - base;
    for (di, dj, w) in [
        (0, 0, (1.0 - f.x) * (1.0 - f.y)),
        (1, 0, f.x * (1.0 - f.y)),
        (0, 1, (1.0 - f.x) * f.y),
        (1, 1, f.x * f.y),
    ] {
        let (i, j) = (base.x + di as f32, base.y + dj as f32);
        let on = i >= 0.0 && j >= 0.0 && i < columns as f32 && j < rows as f32;
        add(on.then(|| j as usize * columns + i as usize), w);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::parallel::{Rayon, Sequential};

    /// `n` particles in an unsorted scatter over (and past) a 20 × 12 rectangle with a solid
    /// border, as `(positions, velocities, kinds)`.
    fn scatter(n: usize) -> (Vec<Vec2>, Vec<Vec2>, Vec<CellKind>) {
        let (nx, ny) = (20, 12);
        let kind = (0..nx * ny)
            .map(|c| {
                let (i, j) = (c % nx, c / nx);
                let border = i == 0 || j == 0 || i == nx - 1;
                if border {
                    CellKind::Solid
                } else {
                    CellKind::Air
                }
            })
            .collect();
        // A fixed, scrambled walk over the rectangle and a cell beyond each side.
        let unit = |k: usize, salt: usize| ((k * 7919 + salt * 104_729) % 1009) as f32 / 1009.0;
        let positions = (0..n)
            .map(|k| Vec2::new(unit(k, 1) * 22.0 - 1.0, unit(k, 2) * 14.0 - 1.0))
            .collect();
        let velocities = (0..n)
            .map(|k| Vec2::new(unit(k, 3) - 0.5, unit(k, 4) - 0.5))
            .collect();
        (positions, velocities, kind)
    }

    /// The splat's sums: the fill, then the face sums.
    type Sums = (Vec<f32>, [Vec<[f32; 2]>; 2]);

    fn run(input: &SplatInput, velocities: &[Vec2], parallel: &impl Parallel, one: bool) -> Sums {
        let (nx, ny) = input.size;
        let mut fill = vec![0.0; nx * ny];
        let mut faces = [vec![[0.0; 2]; (nx + 1) * ny], vec![[0.0; 2]; nx * (ny + 1)]];
        if one {
            let mut band = Band {
                particles: 0..input.positions.len(),
                ..Band::default()
            };
            band.splat_fill(input);
            band.splat_faces(input, velocities);
            let first = band.first_row;
            for (w, &p) in fill[first * nx..].iter_mut().zip(&band.fill) {
                *w += p;
            }
            for (axis, (sums, part)) in faces.iter_mut().zip(&band.face_sums).enumerate() {
                let columns = nx + usize::from(axis == 0);
                for (w, p) in sums[first * columns..].iter_mut().zip(part) {
                    (w[0], w[1]) = (w[0] + p[0], w[1] + p[1]);
                }
            }
        } else {
            let mut bands = Vec::new();
            splat_fill(input, &mut bands, &mut fill, parallel);
            splat_faces(input, velocities, &mut bands, &mut faces, parallel);
        }
        (fill, faces)
    }

    /// Bands of a scatter, unsorted (each band spanning the whole rectangle) and sorted by
    /// height (each a few rows, as the cell-sorted particles), give one band's sums to
    /// rounding, the same bits on one thread and on several, and keep every particle's volume.
    #[test]
    fn bands_add_up_to_one_splat_on_any_number_of_threads() {
        let (mut positions, velocities, kind) = scatter(3000);
        bands_match_one(&positions, &velocities, &kind);
        positions.sort_by(|a, b| a.y.total_cmp(&b.y));
        bands_match_one(&positions, &velocities, &kind);
    }

    fn bands_match_one(positions: &[Vec2], velocities: &[Vec2], kind: &[CellKind]) {
        let input = SplatInput {
            positions,
            cell: 1.0,
            origin: Vec2::ZERO,
            size: (20, 12),
            kind,
            share: 0.25,
        };
        let whole = run(&input, velocities, &Sequential, true);
        let one = run(&input, velocities, &Sequential, false);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        let several = pool.install(|| run(&input, velocities, &Rayon, false));
        assert_eq!(one, several, "the sums depend on the thread count");
        let close = |a: f32, b: f32| (a - b).abs() <= 1e-4 * (1.0 + a.abs());
        assert!(one.0.iter().zip(&whole.0).all(|(&a, &b)| close(a, b)));
        for axis in 0..2 {
            let pairs = one.1[axis].iter().zip(&whole.1[axis]);
            assert!(
                pairs
                    .into_iter()
                    .all(|(a, b)| close(a[0], b[0]) && close(a[1], b[1]))
            );
        }
        // Every particle in a cell that is not solid keeps its whole share; solid cells get
        // none.
        let kept = positions.iter().filter(|x| {
            let on = x.x >= 0.0 && x.y >= 0.0 && x.x < 20.0 && x.y < 12.0;
            on && kind[x.y as usize * 20 + x.x as usize] != CellKind::Solid
        });
        let solid: f32 = one
            .0
            .iter()
            .zip(kind)
            .filter(|(_, k)| **k == CellKind::Solid)
            .map(|(f, _)| f)
            .sum();
        assert_eq!(solid, 0.0);
        let total: f32 = one.0.iter().sum();
        assert!(total <= 0.25 * positions.len() as f32 * 1.0001);
        let least = 0.25 * kept.count() as f32;
        assert!(total >= least * 0.9999, "volume lost: {total} of {least}");
    }
}
