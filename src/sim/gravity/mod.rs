//! Barnes-Hut gravity over plain vectors: the quadtree with monopole or quadrupole cells
//! ([`quadtree`]) and its point-mass and quadrupole sums on SIMD picked at run time ([`kernel`]).

#[expect(
    unsafe_code,
    reason = "the AVX2 and AVX-512 sums, each unsafe block with its SAFETY note"
)]
pub mod kernel;
pub mod quadtree;
