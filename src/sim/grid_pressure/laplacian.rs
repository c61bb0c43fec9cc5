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
    /// Whether each cell is fluid on the rectangle's edge ([`Laplacian::mark_edges`]).
    pub edge: Vec<bool>,
}

impl Laplacian {
    /// Number of cells.
    pub fn len(&self) -> usize {
        self.kind.len()
    }

    /// The four neighbours of cell `c` (left, right, down, up), `None` outside the rectangle.
    #[inline]
    pub fn neighbors(&self, c: usize) -> [Option<usize>; 4] {
        let (i, j) = (c % self.nx, c / self.nx);
        [
            (i > 0).then(|| c - 1),
            (i + 1 < self.nx).then(|| c + 1),
            (j > 0).then(|| c - self.nx),
            (j + 1 < self.ny).then(|| c + self.nx),
        ]
    }

    /// The four diagonal neighbours of cell `c`, `None` outside the rectangle.
    #[inline]
    pub fn diagonals(&self, c: usize) -> [Option<usize>; 4] {
        let (i, j) = (c % self.nx, c / self.nx);
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

    /// Whether cell `c` is an unknown.
    #[inline]
    pub fn is_fluid(&self, c: usize) -> bool {
        self.kind[c] == CellKind::Fluid
    }

    /// `Σ x_n` over the neighbours of fluid cell `c`, for an `x` that is zero off the fluid (so
    /// air and solid neighbours add nothing): the four at once inside the rectangle, those on it
    /// along its edge.
    #[inline]
    fn neighbor_sum<T: Copy + Default + core::ops::Add<Output = T>>(&self, c: usize, x: &[T]) -> T {
        if self.edge[c] {
            return self
                .neighbors(c)
                .into_iter()
                .flatten()
                .fold(T::default(), |sum, n| sum + x[n]);
        }
        (x[c - 1] + x[c + 1]) + (x[c - self.nx] + x[c + self.nx])
    }

    /// `(A x)_c` in f64 (zero off the fluid), for an `x` that is zero off the fluid.
    #[inline]
    pub fn apply_f64(&self, c: usize, x: &[f64]) -> f64 {
        if !self.is_fluid(c) {
            return 0.0;
        }
        f64::from(self.diag[c]) * x[c] - f64::from(self.off) * self.neighbor_sum(c, x)
    }

    /// `(A x)_c` in f32 (zero off the fluid), for an `x` that is zero off the fluid.
    #[inline]
    pub fn apply_f32(&self, c: usize, x: &[f32]) -> f32 {
        if !self.is_fluid(c) {
            return 0.0;
        }
        self.diag[c] * x[c] - self.off * self.neighbor_sum(c, x)
    }

    /// Marks the fluid cells on the rectangle's edge, whose neighbours are looked up one by one
    /// (call it once the kinds are set).
    pub fn mark_edges(&mut self) {
        let (nx, ny) = (self.nx, self.ny);
        self.edge.clear();
        self.edge.extend((0..self.len()).map(|c| {
            let (i, j) = (c % nx, c / nx);
            self.kind[c] == CellKind::Fluid && (i == 0 || j == 0 || i + 1 == nx || j + 1 == ny)
        }));
    }

    /// The equations of the same cells with every air neighbour at a whole cell (`θ = 1`):
    /// what the coarse levels of the multigrid discretise.
    pub fn set_plain_diagonal(&mut self) {
        for c in 0..self.len() {
            self.diag[c] = if self.is_fluid(c) {
                let open = self
                    .neighbors(c)
                    .into_iter()
                    .filter(|&n| self.kind_of(n) != CellKind::Solid)
                    .count();
                open as f32 * self.off
            } else {
                0.0
            };
        }
    }

    /// The equations one level coarser, cells of twice the size: a coarse cell is air if any
    /// of its (up to four) cells is, else fluid if any is, else solid (McAdams, Sifakis & Teran
    /// 2010).
    pub fn coarsen(&self) -> Self {
        let (nx, ny) = (self.nx.div_ceil(2), self.ny.div_ceil(2));
        let mut kind = vec![CellKind::Solid; nx * ny];
        for (c, kind) in kind.iter_mut().enumerate() {
            let (ci, cj) = (c % nx, c / nx);
            let mut any_fluid = false;
            for (i, j) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let (i, j) = (2 * ci + i, 2 * cj + j);
                if i >= self.nx || j >= self.ny {
                    continue;
                }
                match self.kind[j * self.nx + i] {
                    CellKind::Air => {
                        *kind = CellKind::Air;
                        break;
                    }
                    CellKind::Fluid => any_fluid = true,
                    CellKind::Solid => {}
                }
            }
            if *kind != CellKind::Air && any_fluid {
                *kind = CellKind::Fluid;
            }
        }
        let mut coarse = Self {
            nx,
            ny,
            kind,
            diag: vec![0.0; nx * ny],
            off: self.off / 4.0,
            edge: Vec::new(),
        };
        coarse.mark_edges();
        coarse.set_plain_diagonal();
        coarse
    }

    /// Number of fluid cells.
    pub fn fluid_cells(&self) -> usize {
        self.kind.iter().filter(|&&k| k == CellKind::Fluid).count()
    }
}
