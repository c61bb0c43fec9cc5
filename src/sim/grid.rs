//! Uniform-grid neighbour search (a cell list built by counting sort). Pure, no ECS.
//!
//! [`NeighborGrid::rebuild`] bins points into square cells whose side is the search radius and
//! sorts them by cell in O(n); a query then visits the 3×3 block of cells around a point, which
//! in the sorted order is three contiguous runs (one per row). The cell-sorted order is what the
//! solver copies its per-particle data into, so the neighbours of a particle lie next to each
//! other in memory.
//!
//! The grid covers the bounding box of its points; when that box would need more cells than
//! [`NeighborGrid::max_cells`], points outside a window around their centroid are clamped into
//! the border cells. Clamping moves a cell index by at most as much as the point moves, so two
//! points within the search radius always land in adjacent cells and queries stay exact; only
//! their speed suffers for far-flung points.
//!

use super::parallel::{Parallel, Sequential, chunk_size};
use bevy::math::Vec2;
use core::ops::Range;

/// A cell list over a set of 2D points.
#[derive(Debug, Clone, Default)]
pub struct NeighborGrid {
    cell_size: f32,
    inv_cell_size: f32,
    /// Corner of the padded grid: one empty cell outside the points' window on every side, so a
    /// query's 3×3 block never needs clipping.
    origin: Vec2,
    /// Cells across and up the window, padding excluded.
    columns: i32,
    rows: i32,
    /// Cells per row of storage, `columns + 2`.
    stride: i32,
    /// Whether the window is smaller than the points' bounding box (some points clamped).
    windowed: bool,
    /// `cell_start[c]..cell_start[c + 1]` are the sorted slots of padded cell `c` (row-major).
    cell_start: Vec<u32>,
    /// Cell of each input point.
    cell_of: Vec<u32>,
    /// `order[slot]` is the input index of the point in sorted slot `slot`.
    order: Vec<u32>,
    /// `slot_of[input]` is the sorted slot of an input point.
    slot_of: Vec<u32>,
    /// Per cell, whether its 3×3 block holds any point (empty unless
    /// [`mark_occupied_blocks`](Self::mark_occupied_blocks) was called since the last rebuild).
    block_occupied: Vec<bool>,
}

impl NeighborGrid {
    /// An empty grid for the search radius `cell_size` (m, positive).
    pub fn new(cell_size: f32) -> Self {
        let mut grid = Self::default();
        grid.set_cell_size(cell_size);
        grid
    }

    /// Changes the search radius; takes effect at the next [`rebuild`](Self::rebuild).
    pub fn set_cell_size(&mut self, cell_size: f32) {
        debug_assert!(cell_size > 0.0 && cell_size.is_finite());
        self.cell_size = cell_size;
        self.inv_cell_size = 1.0 / cell_size;
    }

    /// The search radius (and cell side), m.
    pub fn cell_size(&self) -> f32 {
        self.cell_size
    }

    /// The largest number of cells [`rebuild`](Self::rebuild) allocates for `points` points.
    pub fn max_cells(points: usize) -> usize {
        4 * points + 4096
    }

    /// Cells a grid of fixed points may take with
    /// [`rebuild_with_budget`](Self::rebuild_with_budget): 4M cells, 16 MiB.
    pub const STATIC_BUDGET: usize = 1 << 22;

    /// Number of points binned at the last rebuild.
    pub fn len(&self) -> usize {
        self.order.len()
    }

    /// Whether the grid holds no points.
    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// Sorted order: `order()[slot]` is the input index of the point stored at `slot`.
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// Inverse of [`order`](Self::order): `slot_of()[input]` is where that input point went.
    pub fn slot_of(&self) -> &[u32] {
        &self.slot_of
    }

    /// Bins `points` into cells and sorts them by cell (stable: points of one cell keep their
    /// input order). O(n + cells), with at most [`max_cells`](Self::max_cells) cells.
    pub fn rebuild(&mut self, points: &[Vec2]) {
        self.rebuild_with_budget(points, Self::max_cells(points.len()));
    }

    /// [`rebuild`](Self::rebuild) allowing up to `max_cells` cells. Points spread thinly (wall
    /// particles round a whole tank) need a budget for the area they span rather than their
    /// number, or far-apart points crowd into the window's edge cells and slow queries down.
    pub fn rebuild_with_budget(&mut self, points: &[Vec2], max_cells: usize) {
        self.rebuild_with(points, max_cells, &Sequential);
    }

    /// [`rebuild_with_budget`](Self::rebuild_with_budget), binning points into cells on
    /// `parallel` (the counting sort itself is sequential).
    pub(crate) fn rebuild_with(
        &mut self,
        points: &[Vec2],
        max_cells: usize,
        parallel: &impl Parallel,
    ) {
        self.block_occupied.clear();
        let n = points.len();
        if n == 0 {
            self.order.clear();
            self.slot_of.clear();
            self.cell_of.clear();
            self.columns = 0;
            self.rows = 0;
            self.stride = 2;
            self.cell_start.clear();
            self.cell_start.push(0);
            return;
        }
        self.place_window(points, max_cells.max(Self::max_cells(n)));

        let cells = (self.stride * (self.rows + 2)) as usize;
        self.cell_start.clear();
        self.cell_start.resize(cells + 1, 0);
        self.cell_of.resize(n, 0);
        let (origin, inv, columns, rows, stride) = (
            self.origin,
            self.inv_cell_size,
            self.columns,
            self.rows,
            self.stride,
        );
        let chunk = chunk_size(n, 16, 8192);
        let mut pieces: Vec<_> = self
            .cell_of
            .chunks_mut(chunk)
            .zip(points.chunks(chunk))
            .collect();
        parallel.for_each(&mut pieces, |(cells, points)| {
            for (cell, &p) in cells.iter_mut().zip(points.iter()) {
                let c = (p - origin) * inv;
                // Points lie right of the padding column except where the window clamps
                // them, so truncation (saturating, NaN to 0) serves as floor.
                let cx = (c.x as i32).clamp(1, columns);
                let cy = (c.y as i32).clamp(1, rows);
                *cell = (cy * stride + cx) as u32;
            }
        });
        for &cell in &self.cell_of {
            self.cell_start[cell as usize + 1] += 1;
        }
        let mut running = 0;
        for start in &mut self.cell_start {
            running += *start;
            *start = running;
        }
        self.order.resize(n, 0);
        self.slot_of.resize(n, 0);
        // Scatter using `cell_start` as running cursors, then shift it back into place.
        for (input, &cell) in self.cell_of.iter().enumerate() {
            let cursor = &mut self.cell_start[cell as usize];
            self.order[*cursor as usize] = input as u32;
            self.slot_of[input] = *cursor;
            *cursor += 1;
        }
        self.cell_start.copy_within(0..cells, 1);
        self.cell_start[0] = 0;
    }

    /// Chooses origin and extent: the bounding box of the points, or a window of at most
    /// `budget` cells around their centroid.
    fn place_window(&mut self, points: &[Vec2], budget: usize) {
        let mut lo = Vec2::splat(f32::INFINITY);
        let mut hi = Vec2::splat(f32::NEG_INFINITY);
        for &p in points {
            // min/max skip NaN; infinities are dropped below.
            lo = lo.min(p);
            hi = hi.max(p);
        }
        if !(lo.is_finite() && hi.is_finite()) {
            // Rare: some point is infinite (or all are NaN). Fall back to the finite ones.
            (lo, hi) = points.iter().filter(|p| p.is_finite()).fold(
                (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)),
                |(lo, hi), &p| (lo.min(p), hi.max(p)),
            );
            if !(lo.is_finite() && hi.is_finite()) {
                (lo, hi) = (Vec2::ZERO, Vec2::ZERO);
            }
        }
        let extent = ((hi - lo) * self.inv_cell_size).floor();
        let mut columns = (extent.x as f64 + 1.0).min(i32::MAX as f64 / 8.0) as i64;
        let mut rows = (extent.y as f64 + 1.0).min(i32::MAX as f64 / 8.0) as i64;
        let mut origin = lo;
        let budget = budget as i64;
        self.windowed = columns * rows > budget;
        if self.windowed {
            // Too sparse for a dense grid: keep a window around the centroid, shrinking the
            // longer side first so thin clouds keep their shape.
            let (sum, counted) = points
                .iter()
                .filter(|p| p.is_finite())
                .fold((bevy::math::DVec2::ZERO, 0usize), |(s, n), p| {
                    (s + p.as_dvec2(), n + 1)
                });
            let centre = (sum / counted.max(1) as f64).as_vec2();
            while columns * rows > budget {
                if columns >= rows {
                    columns = (budget / rows.max(1)).max(1).min(columns - 1).max(1);
                } else {
                    rows = (budget / columns.max(1)).max(1).min(rows - 1).max(1);
                }
            }
            let size = Vec2::new(columns as f32, rows as f32) * self.cell_size;
            let fits = size.cmpge(hi - lo);
            origin = Vec2::select(fits, lo, centre - 0.5 * size);
        }
        self.origin = origin - Vec2::splat(self.cell_size);
        self.columns = columns as i32;
        self.rows = rows as i32;
        self.stride = self.columns + 2;
    }

    /// Records which cells have a point in their 3×3 block, so that queries in empty regions
    /// return after one look-up. Worth it for grids queried far more often than they are rebuilt
    /// (the walls); cleared by the next [`rebuild`](Self::rebuild).
    pub fn mark_occupied_blocks(&mut self) {
        let (stride, rows) = (self.stride, self.rows + 2);
        self.block_occupied = vec![false; self.cell_start.len().saturating_sub(1)];
        for y in 1..rows - 1 {
            for x in 1..stride - 1 {
                let cell = (y * stride + x) as usize;
                if self.cell_start[cell] == self.cell_start[cell + 1] {
                    continue;
                }
                for by in y - 1..=y + 1 {
                    for bx in x - 1..=x + 1 {
                        self.block_occupied[(by * stride + bx) as usize] = true;
                    }
                }
            }
        }
    }

    /// Calls `visit` with the (up to three) runs of sorted slots whose cells touch the 3×3 block
    /// around `p`: every point within [`cell_size`](Self::cell_size) of `p` is in one of them,
    /// visited in a fixed order (row by row, ascending slot).
    #[inline]
    pub fn for_each_run(&self, p: Vec2, mut visit: impl FnMut(Range<usize>)) {
        if self.order.is_empty() {
            return;
        }
        let c = (p - self.origin) * self.inv_cell_size;
        let outside_padding = !(c.x >= 0.0
            && c.y >= 0.0
            && c.x < (self.columns + 2) as f32
            && c.y < (self.rows + 2) as f32);
        if outside_padding && !self.windowed {
            // More than a cell from every point: no neighbours (NaN lands here too).
            return;
        }
        // A query outside a window is clamped to its edge: points clamped into an edge cell
        // are then still within reach (see the module docs), and nothing farther can be a
        // neighbour. (Truncation instead of floor only moves a query left of the padding into
        // the same edge cell.)
        let cx = (c.x as i32).clamp(1, self.columns);
        let cy = (c.y as i32).clamp(1, self.rows);
        let centre = cy * self.stride + cx;
        if !self.block_occupied.is_empty() && !self.block_occupied[centre as usize] {
            return;
        }
        for row in [centre - self.stride, centre, centre + self.stride] {
            let start = self.cell_start[(row - 1) as usize] as usize;
            let end = self.cell_start[(row + 2) as usize] as usize;
            if start < end {
                visit(start..end);
            }
        }
    }

    /// Calls `visit(slot, r²)` for every point within `radius` (≤ the cell size) of `p`, where
    /// `sorted` holds the points in sorted order.
    #[inline]
    pub fn for_each_neighbor(
        &self,
        p: Vec2,
        radius: f32,
        sorted: &[Vec2],
        mut visit: impl FnMut(usize, f32),
    ) {
        let r2_max = radius * radius;
        self.for_each_run(p, |run| {
            for (offset, q) in sorted[run.clone()].iter().enumerate() {
                let r2 = p.distance_squared(*q);
                if r2 < r2_max {
                    visit(run.start + offset, r2);
                }
            }
        });
    }

    /// Copies `values` (in input order) into `sorted` (in sorted order).
    pub fn gather_sorted<T: Copy>(&self, values: &[T], sorted: &mut Vec<T>) {
        sorted.clear();
        sorted.extend(self.order.iter().map(|&i| values[i as usize]));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn brute_force(points: &[Vec2], p: Vec2, radius: f32) -> Vec<usize> {
        let mut v: Vec<usize> = (0..points.len())
            .filter(|&j| p.distance_squared(points[j]) < radius * radius)
            .collect();
        v.sort_unstable();
        v
    }

    fn grid_answer(grid: &NeighborGrid, points: &[Vec2], p: Vec2, radius: f32) -> Vec<usize> {
        let mut sorted = Vec::new();
        grid.gather_sorted(points, &mut sorted);
        let mut v = Vec::new();
        grid.for_each_neighbor(p, radius, &sorted, |slot, _| {
            v.push(grid.order()[slot] as usize)
        });
        v.sort_unstable();
        v
    }

    fn check_all(points: &[Vec2], radius: f32, extra_queries: &[Vec2]) {
        let mut grid = NeighborGrid::new(radius);
        grid.rebuild(points);
        assert_eq!(grid.len(), points.len());
        // order and slot_of are inverse permutations.
        for (slot, &i) in grid.order().iter().enumerate() {
            assert_eq!(grid.slot_of()[i as usize] as usize, slot);
        }
        for &p in points.iter().chain(extra_queries) {
            assert_eq!(
                grid_answer(&grid, points, p, radius),
                brute_force(points, p, radius),
                "query at {p}"
            );
        }
    }

    #[test]
    fn matches_brute_force_on_random_points() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let points: Vec<Vec2> = (0..2000)
            .map(|_| Vec2::new(rng.random_range(-3.0..5.0), rng.random_range(-1.0..2.0)))
            .collect();
        let queries: Vec<Vec2> = (0..200)
            .map(|_| Vec2::new(rng.random_range(-4.0..6.0), rng.random_range(-2.0..3.0)))
            .collect();
        check_all(&points, 0.13, &queries);
    }

    #[test]
    fn matches_brute_force_on_clustered_points() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut points = Vec::new();
        for c in 0..6 {
            let centre = Vec2::new(c as f32 * 1.7, (c % 3) as f32 * -2.1);
            for _ in 0..300 {
                let d = Vec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
                points.push(centre + d * d.abs() * 0.2);
            }
        }
        // Duplicates and a tight clump in one cell.
        points.extend(std::iter::repeat_n(Vec2::new(0.5, 0.5), 50));
        check_all(&points, 0.05, &[]);
    }

    #[test]
    fn points_exactly_on_cell_edges() {
        let h = 0.25;
        let mut points = Vec::new();
        for j in -4..8 {
            for i in -4..8 {
                points.push(Vec2::new(i as f32 * h, j as f32 * h));
                points.push(Vec2::new(i as f32 * h + 0.5 * h, j as f32 * h));
            }
        }
        // Radius equal to the spacing: lattice neighbours at exactly `h` are outside (r < h).
        check_all(&points, h, &[Vec2::new(3.0 * h, -h), Vec2::new(-h, -h)]);
        check_all(&points, h * 1.0001, &[]);
    }

    #[test]
    fn occupied_block_mask_keeps_queries_exact() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        // A ring of points (like tank walls) with an empty middle.
        let points: Vec<Vec2> = (0..600)
            .map(|i| {
                let angle = i as f32 * 0.01047;
                Vec2::from_angle(angle) * rng.random_range(0.9..1.0)
            })
            .collect();
        let mut grid = NeighborGrid::new(0.07);
        grid.rebuild(&points);
        grid.mark_occupied_blocks();
        let mut sorted = Vec::new();
        grid.gather_sorted(&points, &mut sorted);
        for _ in 0..500 {
            let p = Vec2::new(rng.random_range(-1.3..1.3), rng.random_range(-1.3..1.3));
            let mut got = Vec::new();
            grid.for_each_neighbor(p, 0.07, &sorted, |slot, _| {
                got.push(grid.order()[slot] as usize)
            });
            got.sort_unstable();
            assert_eq!(got, brute_force(&points, p, 0.07), "query at {p}");
        }
    }

    #[test]
    fn far_outliers_use_a_window_and_stay_exact() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut points: Vec<Vec2> = (0..500)
            .map(|_| Vec2::new(rng.random_range(0.0..1.0), rng.random_range(0.0..1.0)))
            .collect();
        points.push(Vec2::new(1.0e6, -3.0e5));
        points.push(Vec2::new(1.0e6 + 0.01, -3.0e5));
        points.push(Vec2::new(-2.0e7, 4.0e7));
        let mut grid = NeighborGrid::new(0.02);
        grid.rebuild(&points);
        assert!(grid.columns as usize * grid.rows as usize <= NeighborGrid::max_cells(503));
        assert_eq!(
            grid.cell_start.len() as i32,
            grid.stride * (grid.rows + 2) + 1
        );
        check_all(&points, 0.02, &[Vec2::new(1.0e6, -3.0e5 + 0.015)]);
    }

    #[test]
    fn non_finite_points_do_not_panic() {
        let points = vec![
            Vec2::new(f32::NAN, 0.0),
            Vec2::ONE,
            Vec2::splat(f32::INFINITY),
        ];
        let mut grid = NeighborGrid::new(0.1);
        grid.rebuild(&points);
        assert_eq!(grid.len(), 3);
        assert_eq!(grid_answer(&grid, &points, Vec2::ONE, 0.1), vec![1]);
    }

    #[test]
    fn empty_grid_has_no_neighbors() {
        let mut grid = NeighborGrid::new(0.1);
        grid.rebuild(&[]);
        let mut hits = 0;
        grid.for_each_run(Vec2::ZERO, |_| hits += 1);
        assert_eq!(hits, 0);
    }
}
