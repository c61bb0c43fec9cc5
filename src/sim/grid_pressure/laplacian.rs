//! The pressure equations on a rectangle of cells: the five-point Laplacian over the fluid
//! cells, with air cells as zero-pressure (Dirichlet) neighbours, at a fractional distance on
//! the finest level (the ghost-fluid free surface), and solid cells as closed (Neumann) faces.

/// What a cell of the pressure grid holds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum CellKind {
    /// Empty: zero pressure (the free surface lies between it and a fluid neighbour).
    #[default]
    Air,
    /// Fluid: an unknown pressure.
    Fluid,
    /// A wall or a solid: no flow through its faces but the solid's own.
    Solid,
}

/// The pressure equations `(A p)_c = diag_c p_c − off Σ_{fluid n} p_n` over the fluid cells of
/// an `nx` × `ny` rectangle (row-major, `c = j nx + i`); cells outside it are solid.
///
/// The solvers work on the unknowns alone ([`number_unknowns`](Self::number_unknowns)): the
/// fluid cells numbered in row-major order, each with its four neighbours' numbers, a missing
/// or non-fluid neighbour numbered [`unknowns`](Self::unknowns) (one past the last), the slot
/// every vector over the unknowns keeps at zero. A fluid layer fills a fraction of the
/// rectangle bounding it, so its passes touch only that fraction.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Laplacian {
    /// Columns.
    pub nx: usize,
    /// Rows.
    pub ny: usize,
    /// Each cell's kind.
    pub kind: Vec<CellKind>,
    /// Each fluid cell's diagonal: `off` per fluid neighbour plus `off / θ` per air neighbour
    /// (`θ` the fraction of the way to it where the surface lies), 1/m²; zero off the fluid.
    pub diag: Vec<f32>,
    /// `1/h²`, 1/m²: the coupling to a fluid neighbour (negated).
    pub off: f32,
    /// The rectangle's cell of each unknown.
    pub cells: Vec<u32>,
    /// Each cell's unknown, [`unknowns`](Self::unknowns) off the fluid.
    pub unknown: Vec<u32>,
    /// Each unknown's four neighbours (left, right, down, up) as unknowns, [`unknowns`](Self::unknowns)
    /// where there is none.
    pub stencil: Vec<[u32; 4]>,
    /// Each unknown's diagonal.
    pub unknown_diag: Vec<f32>,
    /// Each cell's rest density ratio (two liquids); empty for one liquid, where every face
    /// couples by `off`.
    pub ratio: Vec<f32>,
    /// With [`ratio`](Self::ratio): each unknown's couplings to its four neighbours,
    /// `off · 2/(r_c + r_n)` (the harmonic mean of `1/r` across the face, symmetric), 1/m².
    pub coupling: Vec<[f32; 4]>,
}

impl Laplacian {
    /// Number of cells.
    pub fn len(&self) -> usize {
        self.kind.len()
    }

    /// Number of unknowns (fluid cells), also the zero slot's index.
    #[inline]
    pub fn unknowns(&self) -> usize {
        self.cells.len()
    }

    /// The four neighbours of cell `c` (left, right, down, up), `None` outside the rectangle.
    #[inline]
    pub fn neighbors(&self, c: usize) -> [Option<usize>; 4] {
        self.neighbors_at(c, (c % self.nx, c / self.nx))
    }

    /// [`neighbors`](Self::neighbors) of cell `c` at column `i`, row `j` (no division).
    #[inline]
    pub fn neighbors_at(&self, c: usize, (i, j): (usize, usize)) -> [Option<usize>; 4] {
        [
            (i > 0).then(|| c - 1),
            (i + 1 < self.nx).then(|| c + 1),
            (j > 0).then(|| c - self.nx),
            (j + 1 < self.ny).then(|| c + self.nx),
        ]
    }

    /// The four diagonal neighbours of cell `c` at column `i`, row `j`, `None` outside the
    /// rectangle.
    #[inline]
    pub fn diagonals_at(&self, c: usize, (i, j): (usize, usize)) -> [Option<usize>; 4] {
        let (left, right, down, up) = (i > 0, i + 1 < self.nx, j > 0, j + 1 < self.ny);
        [
            (left && down).then(|| c - self.nx - 1),
            (right && down).then(|| c - self.nx + 1),
            (left && up).then(|| c + self.nx - 1),
            (right && up).then(|| c + self.nx + 1),
        ]
    }

    /// The kind of neighbour `n` (solid outside the rectangle).
    #[inline]
    pub fn kind_of(&self, n: Option<usize>) -> CellKind {
        n.map_or(CellKind::Solid, |n| self.kind[n])
    }

    /// Makes air of every fluid cell with no path through fluid cells to an air cell, and
    /// returns how many there were. A pocket sealed by walls and solids (water under a body
    /// lying on the floor, a lone cell in a corner) has no pressure level of its own: its
    /// equations are singular, and the conjugate gradients diverged on one (to 10¹⁹ Pa in the
    /// soak). The grid leaves such a pocket to the particles' own solve. `reached` and `stack`
    /// are scratch.
    pub fn open_sealed_pockets(
        &mut self,
        reached: &mut Vec<bool>,
        stack: &mut Vec<usize>,
    ) -> usize {
        reached.clear();
        reached.resize(self.len(), false);
        stack.clear();
        for (c, reached) in reached.iter_mut().enumerate() {
            let open = || {
                self.neighbors(c)
                    .iter()
                    .any(|&n| self.kind_of(n) == CellKind::Air)
            };
            if self.is_fluid(c) && open() {
                *reached = true;
                stack.push(c);
            }
        }
        while let Some(c) = stack.pop() {
            for n in self.neighbors(c).into_iter().flatten() {
                if self.is_fluid(n) && !reached[n] {
                    reached[n] = true;
                    stack.push(n);
                }
            }
        }
        let mut opened = 0;
        for (kind, &reached) in self.kind.iter_mut().zip(reached.iter()) {
            if *kind == CellKind::Fluid && !reached {
                *kind = CellKind::Air;
                opened += 1;
            }
        }
        opened
    }

    /// Whether cell `c` is an unknown.
    #[inline]
    pub fn is_fluid(&self, c: usize) -> bool {
        self.kind[c] == CellKind::Fluid
    }

    /// `(A x)_k` of unknown `k` in f64, `x` over the unknowns with its zero slot.
    #[inline]
    pub fn apply_f64(&self, k: usize, x: &[f64]) -> f64 {
        let [l, r, d, u] = self.stencil[k].map(|n| x[n as usize]);
        let own = f64::from(self.unknown_diag[k]) * x[k];
        match self.coupling.get(k) {
            None => own - f64::from(self.off) * ((l + r) + (d + u)),
            Some(&[a, b, c, e]) => {
                let [a, b, c, e] = [a, b, c, e].map(f64::from);
                own - ((a * l + b * r) + (c * d + e * u))
            }
        }
    }

    /// `(A x)_k` of unknown `k` in f32, `x` over the unknowns with its zero slot.
    #[inline]
    pub fn apply_f32(&self, k: usize, x: &[f32]) -> f32 {
        let [l, r, d, u] = self.stencil[k].map(|n| x[n as usize]);
        let own = self.unknown_diag[k] * x[k];
        match self.coupling.get(k) {
            None => own - self.off * ((l + r) + (d + u)),
            Some(&[a, b, c, e]) => own - ((a * l + b * r) + (c * d + e * u)),
        }
    }

    /// The rest density ratio of cell `c`: one for a single liquid.
    #[inline]
    pub fn ratio_of(&self, c: usize) -> f32 {
        self.ratio.get(c).copied().unwrap_or(1.0)
    }

    /// The coupling across the face between fluid cells `c` and `n`, per `off`: `2/(r_c + r_n)`.
    #[inline]
    pub fn face(&self, c: usize, n: usize) -> f32 {
        if self.ratio.is_empty() {
            1.0
        } else {
            2.0 / (self.ratio[c] + self.ratio[n])
        }
    }

    /// Numbers the unknowns and gathers their stencils and diagonals (call it once the kinds
    /// and the diagonal are set).
    pub fn number_unknowns(&mut self) {
        self.cells.clear();
        let kind = &self.kind;
        self.cells.extend(
            (0..kind.len())
                .filter(|&c| kind[c] == CellKind::Fluid)
                .map(|c| c as u32),
        );
        let none = self.cells.len() as u32;
        self.unknown.clear();
        self.unknown.resize(self.len(), none);
        for (k, &c) in self.cells.iter().enumerate() {
            self.unknown[c as usize] = k as u32;
        }
        let mut stencil = core::mem::take(&mut self.stencil);
        stencil.clear();
        let this = &*self;
        stencil.extend(this.cells.iter().map(|&c| {
            this.neighbors(c as usize)
                .map(|n| n.map_or(none, |n| this.unknown[n]))
        }));
        self.stencil = stencil;
        self.unknown_diag.clear();
        let diag = &self.diag;
        self.unknown_diag
            .extend(self.cells.iter().map(|&c| diag[c as usize]));
        let mut coupling = core::mem::take(&mut self.coupling);
        coupling.clear();
        if !self.ratio.is_empty() {
            let this = &*self;
            coupling.extend(this.cells.iter().map(|&c| {
                let c = c as usize;
                this.neighbors(c).map(|n| match n {
                    Some(n) if this.is_fluid(n) => this.off * this.face(c, n),
                    _ => 0.0,
                })
            }));
        }
        self.coupling = coupling;
    }

    /// The equations of the same cells with every air neighbour at a whole cell (`θ = 1`):
    /// what the coarse levels of the multigrid discretise.
    pub fn set_plain_diagonal(&mut self) {
        for c in 0..self.len() {
            self.diag[c] = if self.is_fluid(c) {
                let open: f32 = (self.neighbors(c).into_iter())
                    .map(|n| match (n, self.kind_of(n)) {
                        (Some(n), CellKind::Fluid) => self.face(c, n),
                        (_, CellKind::Air) => 1.0 / self.ratio_of(c),
                        _ => 0.0,
                    })
                    .sum();
                open * self.off
            } else {
                0.0
            };
        }
    }

    /// The equations one level coarser, cells of twice the size, into `coarse` (its storage
    /// reused): a coarse cell is air if any of its (up to four) cells is, else fluid if any is,
    /// else solid (McAdams, Sifakis & Teran 2010).
    pub fn coarsen_into(&self, coarse: &mut Self) {
        let (nx, ny) = (self.nx.div_ceil(2), self.ny.div_ceil(2));
        (coarse.nx, coarse.ny, coarse.off) = (nx, ny, self.off / 4.0);
        coarse.kind.clear();
        coarse.kind.extend((0..nx * ny).map(|c| {
            let (ci, cj) = (c % nx, c / nx);
            let mut any_fluid = false;
            for (i, j) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let (i, j) = (2 * ci + i, 2 * cj + j);
                if i >= self.nx || j >= self.ny {
                    continue;
                }
                match self.kind[j * self.nx + i] {
                    CellKind::Air => return CellKind::Air,
                    CellKind::Fluid => any_fluid = true,
                    CellKind::Solid => {}
                }
            }
            if any_fluid {
                CellKind::Fluid
            } else {
                CellKind::Solid
            }
        }));
        coarse.ratio.clear();
        if !self.ratio.is_empty() {
            // A coarse cell's ratio: the mean of its fluid cells'.
            coarse.ratio.extend((0..nx * ny).map(|c| {
                let (ci, cj) = (c % nx, c / nx);
                let (mut sum, mut count) = (0.0, 0);
                for (i, j) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let (i, j) = (2 * ci + i, 2 * cj + j);
                    if i < self.nx && j < self.ny && self.is_fluid(j * self.nx + i) {
                        sum += self.ratio[j * self.nx + i];
                        count += 1;
                    }
                }
                if count > 0 { sum / count as f32 } else { 1.0 }
            }));
        }
        coarse.diag.clear();
        coarse.diag.resize(nx * ny, 0.0);
        coarse.set_plain_diagonal();
        coarse.number_unknowns();
    }
}
