//! Pure Barnes-Hut quadtree: bodies sorted along a Morton (Z-order) curve, nodes in flat arrays
//! in depth-first order with skip links (no per-node allocation, no recursion when querying),
//! centre of mass per node, and the opening test "node width / distance < θ". See
//! [`GravityPlugin`](crate::gravity::GravityPlugin).

use super::kernel::{LANES, Quadrupoles, quadrupole_at, sum_point_masses, sum_quadrupoles};
use bevy::math::Vec2;
use bevy::reflect::{Reflect, std_traits::ReflectDefault};
use rayon::prelude::*;

/// Most bits of each coordinate in a Morton code: cells down to 2⁻²⁴ of the bounding square.
/// A sort key packs the code above the body's index in one `u64` (half the bytes to sort of a
/// `(code, index)` pair), so with more than 2¹⁵ bodies the code gets `(63 − index bits) / 2`
/// bits a coordinate: 21 at a million bodies, cells of 5·10⁻⁷ of the square.
const BITS: u32 = 24;

/// Bodies per parallel task when sorting and building subtrees.
const PARALLEL_BODIES: usize = 16_384;

/// Most bodies in a group that shares one interaction list in [`QuadTree::fields`]: larger
/// groups walk the tree less often but sum longer lists (at 1M bodies 16 ran at 0.8 times the
/// speed of 64; 32, 96 and 128 within a few percent of it).
pub const GROUP_SIZE: u32 = 64;

/// One node of the tree. Children follow their parent directly (depth-first order); `next` is
/// the index after the node's whole subtree, so a query skips a subtree in one step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Node {
    /// Centre of mass, m.
    pub center_of_mass: Vec2,
    /// Total mass, kg.
    pub mass: f32,
    /// Lower-left corner of the node's square, m.
    pub min: Vec2,
    /// Side of the node's square, m.
    pub width: f32,
    /// Index of the first node after this subtree.
    pub next: u32,
    /// First body of the node, in sorted order.
    pub first: u32,
    /// Bodies in the node.
    pub count: u32,
    /// A leaf holds its bodies directly; an inner node's children follow it.
    pub leaf: bool,
}

/// The acceleration and potential at a point, from [`QuadTree::field_at`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Field {
    /// Acceleration, m/s².
    pub acceleration: Vec2,
    /// Gravitational potential per unit mass, J/kg (bodies at exactly the query point are left
    /// out, so a body does not count its own mass).
    pub potential: f32,
}

/// What a field query of the [`QuadTree`] needs: the constant, the opening angle and the
/// softening (the tree itself holds the bodies and the [`Multipole`] expansion).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FieldQuery {
    /// Gravitational constant `G`, m³/(kg·s²).
    pub constant: f32,
    /// Opening angle θ: a node of width `w` at distance `d` counts as one mass if `w/d < θ`
    /// (0 sums every body exactly).
    pub theta: f32,
    /// Plummer softening length ε, m: forces go as `d/(d² + ε²)^{3/2}`.
    pub softening: f32,
}

/// How far the far field of a node is expanded.
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
#[reflect(Default, Debug, PartialEq)]
pub enum Multipole {
    /// Each node acts as a point mass at its centre of mass (the classic Barnes-Hut).
    #[default]
    Monopole,
    /// Each node adds its quadrupole moment: the error falls from `(w/d)²` to `(w/d)³`, for
    /// about twice the arithmetic per node.
    Quadrupole,
}

impl Multipole {
    /// Every expansion, for menus.
    pub const ALL: [Multipole; 2] = [Multipole::Monopole, Multipole::Quadrupole];

    /// A short name for menus and logs.
    pub fn label(self) -> &'static str {
        match self {
            Multipole::Monopole => "monopole",
            Multipole::Quadrupole => "quadrupole",
        }
    }
}

/// A Barnes-Hut quadtree over point masses, rebuilt from scratch each step.
#[derive(Debug, Clone, Default)]
pub struct QuadTree {
    nodes: Vec<Node>,
    /// The expansion [`build`](Self::build) prepares and the queries use.
    multipole: Multipole,
    /// `[Qxx, Qyy, Qxy] / m` of each node about its centre of mass, m² (only with
    /// [`Multipole::Quadrupole`]).
    quadrupoles: Vec<[f32; 3]>,
    /// Sorted bodies: x, y, mass (structure of arrays for the leaf loops).
    x: Vec<f32>,
    y: Vec<f32>,
    mass: Vec<f32>,
    /// Original index of each sorted body.
    order: Vec<u32>,
    /// Bodies given to the last build, left-out ones included.
    input_len: usize,
    /// Scratch of [`fields`](Self::fields): the fields in tree order, and the scatter's runs.
    sorted_fields: Vec<Field>,
    staging: Vec<(u32, Field)>,
    /// Sort keys: Morton code above the body's index.
    keys: Vec<u64>,
}

impl QuadTree {
    /// An empty tree.
    pub fn new() -> Self {
        Self::default()
    }

    /// Expands nodes this far from the next [`build`](Self::build) on.
    pub fn set_multipole(&mut self, multipole: Multipole) {
        self.multipole = multipole;
    }

    /// The expansion the next [`build`](Self::build) prepares.
    pub fn multipole(&self) -> Multipole {
        self.multipole
    }

    /// Rebuilds the tree over `positions` (m) and `masses` (kg), leaves holding at most
    /// `leaf_capacity` bodies (more only where bodies share a position). Bodies with a
    /// non-finite position or a non-finite or non-positive mass are left out. Sorting and the
    /// top of the tree run in parallel on the current rayon pool for large inputs (the plugin
    /// calls it on the crate's compute pool).
    pub fn build(&mut self, positions: &[Vec2], masses: &[f32], leaf_capacity: usize) {
        let leaf_capacity = leaf_capacity.max(1);
        let n = positions.len().min(masses.len());
        self.input_len = n;
        let (min, max, count) = bounds(positions, masses, n);
        self.nodes.clear();
        self.keys.clear();
        if count == 0 {
            self.x.clear();
            self.y.clear();
            self.mass.clear();
            self.order.clear();
            self.quadrupoles.clear();
            return;
        }
        // A square a little larger than the bounding box, so every body quantises inside it.
        let width = (max - min).max_element().max(f32::MIN_POSITIVE) * (1.0 + 1e-5) + 1e-30;
        let index_bits = (usize::BITS - (n.max(2) - 1).leading_zeros()).max(1);
        let bits = ((63 - index_bits) / 2).min(BITS);
        self.sort_bodies(positions, masses, count, (min, width), (bits, index_bits));
        let builder = Builder {
            keys: &self.keys,
            code_shift: index_bits,
            bits,
            x: &self.x,
            y: &self.y,
            mass: &self.mass,
            leaf_capacity,
        };
        let mut nodes = std::mem::take(&mut self.nodes);
        builder.subtree(0, count, 0, min, width, &mut nodes);
        self.nodes = nodes;
        self.quadrupoles.clear();
        if self.multipole == Multipole::Quadrupole {
            self.compute_quadrupoles();
        }
    }

    /// Sorts the `count` valid bodies by Morton key in the square at `min` of side `width`
    /// (`bits` per coordinate, the body's index in the low `index_bits`), and copies their
    /// positions and masses into that order.
    fn sort_bodies(
        &mut self,
        positions: &[Vec2],
        masses: &[f32],
        count: usize,
        (min, width): (Vec2, f32),
        (bits, index_bits): (u32, u32),
    ) {
        let n = positions.len().min(masses.len());
        let scale = (1u64 << bits) as f32 / width;
        let quantise = |v: f32| ((v * scale) as u64).min((1u64 << bits) - 1);
        // Real keys are below 2⁶³; left-out bodies get `u64::MAX`, so they sort to the end and
        // are cut off. Keys carry the index, so they are unique and the sorted order does not
        // depend on the thread count.
        let key = |i: u32| {
            if valid(positions, masses, i as usize) {
                let p = positions[i as usize] - min;
                (morton(quantise(p.x), quantise(p.y)) << index_bits) | i as u64
            } else {
                u64::MAX
            }
        };
        self.keys.par_extend(
            (0..n as u32)
                .into_par_iter()
                .with_min_len(PARALLEL_BODIES)
                .map(key),
        );
        self.keys.par_sort_unstable();
        self.keys.truncate(count);
        let index_mask = (1u64 << index_bits) - 1;
        self.order.clear();
        self.order
            .par_extend(self.keys.par_iter().map(|&k| (k & index_mask) as u32));
        let order = &self.order;
        // One read of each body's position for both coordinates.
        order
            .par_iter()
            .map(|&i| (positions[i as usize].x, positions[i as usize].y))
            .unzip_into_vecs(&mut self.x, &mut self.y);
        self.mass.clear();
        self.mass
            .par_extend(order.par_iter().map(|&i| masses[i as usize]));
    }

    /// The quadrupole moment per unit mass of every node about its centre of mass (kept per
    /// unit mass, so it stays in range at any mass): leaves from their bodies
    /// (in parallel), inner nodes from their children by the parallel-axis rule
    /// `Q = Σ (Q_c + m_c (3 δδᵀ − |δ|² I))`, `δ` from the node's centre to the child's (children
    /// come after their parent, so one backward pass sees every child first). In `f64`.
    fn compute_quadrupoles(&mut self) {
        let moment = |m: f64, d: [f64; 2]| {
            let r2 = d[0] * d[0] + d[1] * d[1];
            [
                m * (3.0 * d[0] * d[0] - r2),
                m * (3.0 * d[1] * d[1] - r2),
                m * 3.0 * d[0] * d[1],
            ]
        };
        let (x, y, mass) = (&self.x, &self.y, &self.mass);
        let mut q: Vec<[f64; 3]> = self
            .nodes
            .par_iter()
            .with_min_len(1024)
            .map(|node| {
                let mut total = [0.0f64; 3];
                if node.leaf {
                    let c = node.center_of_mass;
                    for k in node.first as usize..(node.first + node.count) as usize {
                        let d = [(x[k] - c.x) as f64, (y[k] - c.y) as f64];
                        let add = moment(mass[k] as f64, d);
                        (0..3).for_each(|i| total[i] += add[i]);
                    }
                }
                total
            })
            .collect();
        for i in (0..self.nodes.len()).rev() {
            let node = self.nodes[i];
            if node.leaf {
                continue;
            }
            let mut total = [0.0f64; 3];
            let mut child = i + 1;
            while child < node.next as usize {
                let c = &self.nodes[child];
                let d = [
                    (c.center_of_mass.x - node.center_of_mass.x) as f64,
                    (c.center_of_mass.y - node.center_of_mass.y) as f64,
                ];
                let shift = moment(c.mass as f64, d);
                (0..3).for_each(|k| total[k] += q[child][k] + shift[k]);
                child = c.next as usize;
            }
            q[i] = total;
        }
        let per_mass = |node: &Node, q: &[f64; 3]| {
            let m = node.mass as f64;
            q.map(|v| if m > 0.0 { (v / m) as f32 } else { 0.0 })
        };
        self.quadrupoles
            .extend(self.nodes.iter().zip(&q).map(|(node, q)| per_mass(node, q)));
    }

    /// The nodes, root first, in depth-first order.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// Bodies in the tree.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether the tree holds no body.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Original indices of the bodies, in the tree's (Morton) order.
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// Acceleration and potential at `p` from every body in the tree (bodies exactly at `p`
    /// are left out).
    pub fn field_at(&self, p: Vec2, gravity: &FieldQuery) -> Field {
        let theta_sq = gravity.theta * gravity.theta;
        let eps_sq = gravity.softening * gravity.softening;
        let mut acceleration = Vec2::ZERO;
        let mut potential = 0.0f32;
        let mut i = 0usize;
        let nodes = &self.nodes;
        while i < nodes.len() {
            let node = &nodes[i];
            if node.leaf {
                let range = node.first as usize..(node.first + node.count) as usize;
                let (a, phi) = sum_point_masses(
                    p,
                    &self.x[range.clone()],
                    &self.y[range.clone()],
                    &self.mass[range],
                    eps_sq,
                );
                acceleration += a;
                potential += phi;
                i = node.next as usize;
                continue;
            }
            let d = node.center_of_mass - p;
            let r2 = d.length_squared();
            let inside = p.x >= node.min.x
                && p.y >= node.min.y
                && p.x < node.min.x + node.width
                && p.y < node.min.y + node.width;
            if !inside && node.width * node.width < theta_sq * r2 {
                if let Some(&q) = self.quadrupoles.get(i) {
                    let (a, phi) = quadrupole_at(p, node.center_of_mass, node.mass, q, eps_sq);
                    acceleration += a;
                    potential += phi;
                } else {
                    let s = r2 + eps_sq;
                    let inv = 1.0 / (s * s.sqrt());
                    acceleration += d * (node.mass * inv);
                    potential -= node.mass / s.sqrt();
                }
                i = node.next as usize;
            } else {
                i += 1;
            }
        }
        Field {
            acceleration: acceleration * gravity.constant,
            potential: potential * gravity.constant,
        }
    }
}

impl QuadTree {
    /// The field at every body given to [`build`](Self::build), in the order given there (zero
    /// for bodies the build left out): a group walk. Bodies are taken in groups of at most
    /// 64 neighbours along the curve; each group walks the tree once, opening a
    /// node unless `width < θ · d` for the distance `d` from the node's centre of mass to the
    /// group's bounding box (so the test holds for every body in the group, and the result is
    /// at least as accurate as [`field_at`](Self::field_at) per body), and then every body of
    /// the group sums the shared list of sources on SIMD lanes. Groups run in
    /// parallel on rayon; each body's sum runs in a fixed order, so the result does not depend
    /// on the thread count.
    pub fn fields(&mut self, gravity: &FieldQuery, out: &mut Vec<Field>) {
        let mut sorted = std::mem::take(&mut self.sorted_fields);
        self.sorted_fields_into(gravity, &mut sorted);
        scatter(&self.order, &sorted, self.input_len, out, &mut self.staging);
        self.sorted_fields = sorted;
    }

    /// The field at every body of the tree, in the tree's (Morton) order.
    fn sorted_fields_into(&self, gravity: &FieldQuery, out: &mut Vec<Field>) {
        out.clear();
        out.resize(self.len(), Field::default());
        if self.is_empty() {
            return;
        }
        let mut groups = Vec::new();
        let mut i = 0usize;
        while i < self.nodes.len() {
            let node = &self.nodes[i];
            if node.count <= GROUP_SIZE || node.leaf {
                groups.push(i as u32);
                i = node.next as usize;
            } else {
                i += 1;
            }
        }
        // Split the output into one slice per group (groups are contiguous and in order).
        let mut slices: Vec<(u32, &mut [Field])> = Vec::with_capacity(groups.len());
        let mut rest = out.as_mut_slice();
        for &g in &groups {
            let (here, tail) = rest.split_at_mut(self.nodes[g as usize].count as usize);
            slices.push((g, here));
            rest = tail;
        }
        let eps_sq = gravity.softening * gravity.softening;
        slices.into_par_iter().for_each_init(
            || (Vec::new(), Vec::new(), Vec::new(), Quadrupoles::default()),
            |(lx, ly, lm, lq), (g, fields)| {
                let group = &self.nodes[g as usize];
                let range = group.first as usize..(group.first + group.count) as usize;
                self.interaction_list(range.clone(), gravity.theta, lx, ly, lm, lq);
                for (k, field) in range.zip(fields.iter_mut()) {
                    let p = Vec2::new(self.x[k], self.y[k]);
                    let (mut a, mut phi) = sum_point_masses(p, lx, ly, lm, eps_sq);
                    if !lq.is_empty() {
                        let (qa, qphi) = sum_quadrupoles(p, lq, eps_sq);
                        a += qa;
                        phi += qphi;
                    }
                    *field = Field {
                        acceleration: a * gravity.constant,
                        potential: phi * gravity.constant,
                    };
                }
            },
        );
    }

    /// The sources that act on the sorted bodies `range`: single bodies, and accepted nodes
    /// as point masses, written to `x`, `y`, `m`; with [`Multipole::Quadrupole`] the accepted
    /// nodes go to `nodes` instead, with their moments.
    fn interaction_list(
        &self,
        range: core::ops::Range<usize>,
        theta: f32,
        x: &mut Vec<f32>,
        y: &mut Vec<f32>,
        m: &mut Vec<f32>,
        nodes: &mut Quadrupoles,
    ) {
        x.clear();
        y.clear();
        m.clear();
        nodes.clear();
        let mut lo = Vec2::splat(f32::INFINITY);
        let mut hi = Vec2::splat(f32::NEG_INFINITY);
        for k in range {
            let p = Vec2::new(self.x[k], self.y[k]);
            lo = lo.min(p);
            hi = hi.max(p);
        }
        let theta_sq = theta * theta;
        let mut i = 0usize;
        while i < self.nodes.len() {
            let node = &self.nodes[i];
            if node.leaf {
                let bodies = node.first as usize..(node.first + node.count) as usize;
                // A loop, not `extend_from_slice`: a leaf holds a handful of bodies, and three
                // `memmove` calls per leaf cost more than the copies (7% of a step at 1M).
                for k in bodies {
                    x.push(self.x[k]);
                    y.push(self.y[k]);
                    m.push(self.mass[k]);
                }
                i = node.next as usize;
                continue;
            }
            let node_max = node.min + Vec2::splat(node.width);
            let overlaps = node.min.x <= hi.x
                && node.min.y <= hi.y
                && node_max.x >= lo.x
                && node_max.y >= lo.y;
            let gap = (lo - node.center_of_mass)
                .max(node.center_of_mass - hi)
                .max(Vec2::ZERO);
            if !overlaps && node.width * node.width < theta_sq * gap.length_squared() {
                if let Some(&q) = self.quadrupoles.get(i) {
                    nodes.push(node.center_of_mass, node.mass, q);
                } else {
                    x.push(node.center_of_mass.x);
                    y.push(node.center_of_mass.y);
                    m.push(node.mass);
                }
                i = node.next as usize;
            } else {
                i += 1;
            }
        }
        // Zero masses up to whole SIMD chunks: they add exactly nothing (see `kernel`).
        let padded = x.len().div_ceil(LANES) * LANES;
        x.resize(padded, 0.0);
        y.resize(padded, 0.0);
        m.resize(padded, 0.0);
        nodes.pad();
    }
}

/// Outputs per block of [`scatter`]: 65,536 fields (768 KiB) fit the L2 cache (8,192 took
/// twice as long at 1M bodies, 262,144 as long).
const SCATTER_BLOCK: usize = 1 << 16;

/// `out[order[k]] = values[k]` for every `k`, into `out` of length `len` (zero where no `k`
/// writes), in two cache-friendly passes: the values are first dealt, in order, to one run of
/// `staging` per block of outputs; then the blocks are filled in parallel, each from its own
/// run. Writing straight to random places in a large output costs a cache and TLB miss per
/// value: at 1M bodies that took 3 to 6 times as long.
fn scatter<T: Copy + Default + Send + Sync>(
    order: &[u32],
    values: &[T],
    len: usize,
    out: &mut Vec<T>,
    staging: &mut Vec<(u32, T)>,
) {
    let blocks = len.div_ceil(SCATTER_BLOCK);
    let mut starts = vec![0usize; blocks + 1];
    for &i in order {
        starts[i as usize / SCATTER_BLOCK + 1] += 1;
    }
    for b in 0..blocks {
        starts[b + 1] += starts[b];
    }
    // Every run is rewritten in full, so the staging needs no clearing.
    staging.resize(order.len(), (0, T::default()));
    let mut cursor = starts.clone();
    for (&i, &value) in order.iter().zip(values) {
        let b = i as usize / SCATTER_BLOCK;
        staging[cursor[b]] = (i, value);
        cursor[b] += 1;
    }
    if order.len() < len || out.len() != len {
        // Some outputs are not written: start from zero.
        out.clear();
        out.resize(len, T::default());
    }
    out.par_chunks_mut(SCATTER_BLOCK)
        .enumerate()
        .for_each(|(b, chunk)| {
            for &(i, value) in &staging[starts[b]..starts[b + 1]] {
                chunk[i as usize - b * SCATTER_BLOCK] = value;
            }
        });
}

/// Direct summation over every body: the exact answer the tree approximates (O(n) per point).
pub fn direct_field_at(p: Vec2, positions: &[Vec2], masses: &[f32], gravity: &FieldQuery) -> Field {
    let eps_sq = gravity.softening * gravity.softening;
    let mut acceleration = Vec2::ZERO;
    let mut potential = 0.0f32;
    for (q, &m) in positions.iter().zip(masses) {
        if !(q.is_finite() && m.is_finite() && m > 0.0) {
            continue;
        }
        let d = *q - p;
        let r2 = d.length_squared();
        if r2 > 0.0 {
            let s = r2 + eps_sq;
            let inv_r = 1.0 / s.sqrt();
            acceleration += d * (m * inv_r * inv_r * inv_r);
            potential -= m * inv_r;
        }
    }
    Field {
        acceleration: acceleration * gravity.constant,
        potential: potential * gravity.constant,
    }
}

/// Interleaves the bits of `x` and `y` (x in the even bits).
fn morton(x: u64, y: u64) -> u64 {
    fn spread(mut v: u64) -> u64 {
        v &= 0xffff_ffff;
        v = (v | (v << 16)) & 0x0000_ffff_0000_ffff;
        v = (v | (v << 8)) & 0x00ff_00ff_00ff_00ff;
        v = (v | (v << 4)) & 0x0f0f_0f0f_0f0f_0f0f;
        v = (v | (v << 2)) & 0x3333_3333_3333_3333;
        v = (v | (v << 1)) & 0x5555_5555_5555_5555;
        v
    }
    spread(x) | (spread(y) << 1)
}

/// Builds subtrees over ranges of the sorted bodies.
struct Builder<'a> {
    keys: &'a [u64],
    /// The code is `key >> code_shift`.
    code_shift: u32,
    /// Bits of each coordinate in the codes.
    bits: u32,
    x: &'a [f32],
    y: &'a [f32],
    mass: &'a [f32],
    leaf_capacity: usize,
}

impl Builder<'_> {
    /// Appends the subtree over sorted bodies `lo..hi` in the square at `min` of side `width`,
    /// at depth `level`, to `nodes`; `next` links are indices into `nodes`. Subtrees of at least
    /// `4 × PARALLEL_BODIES` bodies build their four children in parallel, each into a vector of
    /// its own that is then appended with its links shifted; smaller ones build in place.
    fn subtree(
        &self,
        lo: usize,
        hi: usize,
        level: u32,
        min: Vec2,
        width: f32,
        nodes: &mut Vec<Node>,
    ) {
        let count = hi - lo;
        if count <= self.leaf_capacity || level >= self.bits {
            let (mass, center_of_mass) = self.center_of_mass(lo, hi);
            nodes.push(Node {
                center_of_mass,
                mass,
                min,
                width,
                next: nodes.len() as u32 + 1,
                first: lo as u32,
                count: count as u32,
                leaf: true,
            });
            return;
        }
        // The quadrant of each body is the next two bits of its code; the range is sorted, so
        // each quadrant is a contiguous run.
        let shift = self.code_shift + 2 * (self.bits - 1 - level);
        let mut bounds = [lo; 5];
        for q in 1..4u64 {
            bounds[q as usize] = lo + self.keys[lo..hi].partition_point(|k| ((k >> shift) & 3) < q);
        }
        bounds[4] = hi;
        let half = 0.5 * width;
        let child_min = |q: usize| min + Vec2::new((q & 1) as f32 * half, (q >> 1) as f32 * half);
        let parent = nodes.len();
        nodes.push(Node::default());
        let mut roots = [usize::MAX; 4];
        let child = |q: usize, out: &mut Vec<Node>| {
            let (lo, hi) = (bounds[q], bounds[q + 1]);
            self.subtree(lo, hi, level + 1, child_min(q), half, out);
        };
        let occupied = |q: usize| bounds[q] < bounds[q + 1];
        if count >= 4 * PARALLEL_BODIES {
            let children: Vec<Vec<Node>> = (0..4)
                .into_par_iter()
                .map(|q| {
                    let mut nodes = Vec::new();
                    if occupied(q) {
                        child(q, &mut nodes);
                    }
                    nodes
                })
                .collect();
            for (q, built) in children
                .into_iter()
                .enumerate()
                .filter(|(q, _)| occupied(*q))
            {
                let offset = nodes.len() as u32;
                roots[q] = nodes.len();
                nodes.extend(built.into_iter().map(|mut node| {
                    node.next += offset;
                    node
                }));
            }
        } else {
            for q in (0..4).filter(|&q| occupied(q)) {
                roots[q] = nodes.len();
                child(q, nodes);
            }
        }
        let (mut mass, mut moment) = (0.0f64, [0.0f64; 2]);
        for &root in roots.iter().filter(|&&r| r != usize::MAX) {
            let root = &nodes[root];
            mass += root.mass as f64;
            moment[0] += root.mass as f64 * root.center_of_mass.x as f64;
            moment[1] += root.mass as f64 * root.center_of_mass.y as f64;
        }
        nodes[parent] = Node {
            center_of_mass: centre(mass, moment),
            mass: mass as f32,
            min,
            width,
            next: nodes.len() as u32,
            first: lo as u32,
            count: count as u32,
            leaf: false,
        };
    }

    fn center_of_mass(&self, lo: usize, hi: usize) -> (f32, Vec2) {
        let (mut mass, mut moment) = (0.0f64, [0.0f64; 2]);
        for k in lo..hi {
            let m = self.mass[k] as f64;
            mass += m;
            moment[0] += m * self.x[k] as f64;
            moment[1] += m * self.y[k] as f64;
        }
        (mass as f32, centre(mass, moment))
    }
}

fn centre(mass: f64, moment: [f64; 2]) -> Vec2 {
    if mass > 0.0 {
        Vec2::new((moment[0] / mass) as f32, (moment[1] / mass) as f32)
    } else {
        Vec2::ZERO
    }
}

/// Whether body `i` takes part: a finite position and a finite positive mass.
fn valid(positions: &[Vec2], masses: &[f32], i: usize) -> bool {
    positions[i].is_finite() && masses.get(i).is_some_and(|m| m.is_finite() && *m > 0.0)
}

/// The bounding box of the first `n` bodies that take part, and how many there are.
fn bounds(positions: &[Vec2], masses: &[f32], n: usize) -> (Vec2, Vec2, usize) {
    let empty = || {
        (
            Vec2::splat(f32::INFINITY),
            Vec2::splat(f32::NEG_INFINITY),
            0usize,
        )
    };
    (0..n)
        .into_par_iter()
        .with_min_len(PARALLEL_BODIES)
        .fold(empty, |(lo, hi, count), i| {
            if valid(positions, masses, i) {
                (lo.min(positions[i]), hi.max(positions[i]), count + 1)
            } else {
                (lo, hi, count)
            }
        })
        .reduce(empty, |a, b| (a.0.min(b.0), a.1.max(b.1), a.2 + b.2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn cloud(n: usize, seed: u64) -> (Vec<Vec2>, Vec<f32>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let p = (0..n)
            .map(|_| Vec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)))
            .collect();
        let m = (0..n).map(|_| rng.random_range(0.5..1.5)).collect();
        (p, m)
    }

    const G: FieldQuery = FieldQuery {
        constant: 1.0,
        theta: 0.5,
        softening: 0.0,
    };

    #[test]
    fn tree_holds_every_body_once_with_the_total_mass() {
        let (p, m) = cloud(3000, 1);
        let mut tree = QuadTree::new();
        tree.build(&p, &m, 8);
        assert_eq!(tree.len(), 3000);
        let mut seen = tree.order().to_vec();
        seen.sort_unstable();
        assert!(seen.iter().enumerate().all(|(i, &k)| i as u32 == k));
        let root = tree.nodes()[0];
        let total: f64 = m.iter().map(|&m| m as f64).sum();
        assert!((root.mass as f64 - total).abs() < 1e-3 * total);
        assert_eq!(root.next as usize, tree.nodes().len());
        // Leaves partition the bodies, and none holds more than the capacity.
        let leaves: Vec<&Node> = tree.nodes().iter().filter(|n| n.leaf).collect();
        assert_eq!(leaves.iter().map(|n| n.count).sum::<u32>(), 3000);
        assert!(leaves.iter().all(|n| n.count <= 8));
    }

    #[test]
    fn theta_zero_is_direct_summation() {
        let (p, m) = cloud(500, 2);
        let mut tree = QuadTree::new();
        tree.build(&p, &m, 4);
        let exact = FieldQuery { theta: 0.0, ..G };
        for &q in p.iter().take(50) {
            let a = tree.field_at(q, &exact);
            let b = direct_field_at(q, &p, &m, &exact);
            assert!((a.acceleration - b.acceleration).length() <= 1e-4 * b.acceleration.length());
            assert!((a.potential - b.potential).abs() <= 1e-4 * b.potential.abs());
        }
    }

    #[test]
    fn group_walk_is_at_least_as_accurate_as_the_single_walk() {
        let (p, m) = cloud(5000, 4);
        let mut tree = QuadTree::new();
        tree.build(&p, &m, 8);
        let mut fields = Vec::new();
        for theta in [0.0, 0.5, 1.0] {
            let g = FieldQuery { theta, ..G };
            tree.fields(&g, &mut fields);
            assert_eq!(fields.len(), 5000);
            let (mut group_error, mut single_error) = (0.0f64, 0.0f64);
            for (k, field) in fields.iter().enumerate().step_by(25) {
                let q = p[k];
                let exact = direct_field_at(q, &p, &m, &g).acceleration;
                group_error += ((field.acceleration - exact).length() / exact.length()) as f64;
                let single = tree.field_at(q, &g).acceleration;
                single_error += ((single - exact).length() / exact.length()) as f64;
            }
            // Up to float rounding (1e-5 per sample), never worse than the single walk.
            assert!(
                group_error <= single_error + 200.0 * 1e-5,
                "θ {theta}: {group_error} vs {single_error}"
            );
            if theta == 0.0 {
                assert!(group_error / 200.0 < 1e-5);
            }
        }
    }

    #[test]
    fn coincident_single_and_far_bodies_stay_finite() {
        let mut tree = QuadTree::new();
        // One body: no force on itself.
        tree.build(&[Vec2::new(3.0, 4.0)], &[2.0], 8);
        assert_eq!(tree.field_at(Vec2::new(3.0, 4.0), &G), Field::default());
        // Twenty bodies at one point, with and without softening: finite, and a body there
        // feels nothing from the others.
        let p = vec![Vec2::ONE; 20];
        let m = vec![1.0; 20];
        tree.build(&p, &m, 4);
        assert_eq!(tree.len(), 20);
        for softening in [0.0, 0.1] {
            let g = FieldQuery { softening, ..G };
            let at = tree.field_at(Vec2::ONE, &g);
            assert_eq!(at.acceleration, Vec2::ZERO);
            let beside = tree.field_at(Vec2::new(2.0, 1.0), &g).acceleration;
            assert!(beside.is_finite() && beside.x < 0.0);
        }
        // A body a million metres out, and rejected ones.
        let p = vec![Vec2::ZERO, Vec2::X, Vec2::new(1.0e6, -1.0e6), Vec2::NAN];
        let m = vec![1.0, 1.0, 1.0, 1.0];
        tree.build(&p, &m, 1);
        assert_eq!(tree.len(), 3);
        let a = tree.field_at(Vec2::ZERO, &G).acceleration;
        assert!(a.is_finite() && (a.x - 1.0).abs() < 1e-3);
        tree.build(&[], &[], 8);
        assert!(tree.is_empty());
        assert_eq!(tree.field_at(Vec2::ZERO, &G), Field::default());
    }

    #[test]
    fn build_is_the_same_for_any_thread_count() {
        let (p, m) = cloud(100_000, 3);
        let build = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut tree = QuadTree::new();
                tree.build(&p, &m, 8);
                (tree.nodes().to_vec(), tree.order().to_vec())
            })
        };
        assert_eq!(build(1), build(3));
    }
}
