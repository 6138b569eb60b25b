//! Height blocks: a height-field tile's fine surface summarised over blocks of whole fine cells,
//! about [`BLOCK_CELLS`] a side, for the CPU proof that tiles are hidden by height fields
//! (`crate::cull::hidden`).
//!
//! Contract of [`height_blocks`]: given the tile's `w` × `h` samples (each the f32 position of the
//! vertex drawn there, None for a hole) and its triangles the lattice's (each fine cell, two
//! triangles over its corners where they are finite, as `super::tile_heightfield` makes them):
//! * block (p, q) spans local sample columns `cols[p]..=cols[p + 1]` and rows
//!   `rows[q]..=rows[q + 1]`, its cells those between; blocks share their border samples;
//! * its `lo..hi` is the box of its finite samples' positions, so it holds every fine triangle of
//!   its cells (a triangle's corners are samples of its cell), and is empty (lo > hi) without any;
//! * `complete` when all of its samples are finite: then its cells' triangles cover its whole
//!   footprint (the lattice's two triangles of every cell);
//! * `plane` (its heights at the block's corner samples (c0, r0), (c1, r0), (c0, r1), linear in the
//!   sample indices) and `residual`: every point of its triangles lies within `residual`
//!   vertically of the plane (the difference of two functions linear over each triangle is
//!   largest at a corner, a sample, whose distance is measured against the f32 plane as stored
//!   and rounded up). The plane is the least-squares fit of its finite samples (flat at their mid
//!   height where they do not span a plane), so that a dipping block is a thin slanted prism.
//!
//! A tile's blocks tell how high its surface lies over a part of it: a dipping horizon 70 m high
//! over a tile spans about a seventh of that over a block of a 55-cell tile, well under the
//! 20-40 m between stacked horizons.

/// Cells per block side (blocks of a tile side are as even as [`bounds`] makes them).
pub const BLOCK_CELLS: usize = 8;

/// One block of a tile: the box of its finite samples and whether it has no hole.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Block {
    pub lo: [f32; 3],
    pub hi: [f32; 3],
    pub complete: bool,
    pub plane: [f32; 3],
    pub residual: f32,
}

impl Block {
    /// Whether the block has no finite sample (then it holds no triangle).
    pub fn is_empty(&self) -> bool {
        self.lo[0] > self.hi[0]
    }
}

/// A tile's blocks (see the module's contract).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HeightBlocks {
    /// Local sample boundaries of the block columns and rows: 0 = cols[0] < ... = w - 1.
    pub cols: Vec<usize>,
    pub rows: Vec<usize>,
    /// Row-major by block row, then column.
    pub blocks: Vec<Block>,
    /// [`Self::node_plane`] of all the blocks, computed once.
    pub whole: Option<([f64; 3], f64)>,
}

impl HeightBlocks {
    pub fn columns(&self) -> usize {
        self.cols.len() - 1
    }
    pub fn block(&self, p: usize, q: usize) -> &Block {
        &self.blocks[q * self.columns() + p]
    }
}

impl HeightBlocks {
    /// Block (p, q)'s plane at local sample (c, r) (linear in the sample indices).
    pub fn plane_at(&self, p: usize, q: usize, c: f64, r: f64) -> f64 {
        let [z00, z10, z01] = self.block(p, q).plane.map(f64::from);
        let (c0, r0) = (self.cols[p] as f64, self.rows[q] as f64);
        let (w, h) = (self.cols[p + 1] as f64 - c0, self.rows[q + 1] as f64 - r0);
        z00 + (z10 - z00) * (c - c0) / w + (z01 - z00) * (r - r0) / h
    }

    /// A plane and a residual for blocks `p0..p1` × `q0..q1` together: the plane (its heights at
    /// the local samples (cols[p0], rows[q0]), (cols[p1], rows[q0]), (cols[p0], rows[q1])) fitted
    /// to the corners of their non-empty blocks' planes, and a bound on the vertical distance
    /// from it of every point of their triangles: over each block, the largest difference of the
    /// two planes at its corners (two planes over a parallelogram differ most at a corner) plus
    /// the block's residual, rounded up. None without a non-empty block or for a degenerate fit.
    pub fn node_plane(&self, (p0, p1): (usize, usize), (q0, q1): (usize, usize)) -> Option<([f64; 3], f64)> {
        let blocks =
            || (q0..q1).flat_map(move |q| (p0..p1).map(move |p| (p, q))).filter(|&(p, q)| !self.block(p, q).is_empty());
        let corners = |(p, q): (usize, usize)| {
            [(p, q), (p + 1, q), (p, q + 1), (p + 1, q + 1)].map(|(i, j)| (self.cols[i] as f64, self.rows[j] as f64))
        };
        let points = blocks().flat_map(|b| corners(b).map(|(c, r)| ((c, r), self.plane_at(b.0, b.1, c, r))));
        let (z0, a, b) = fit_plane(points)?;
        let node = |c: f64, r: f64| z0 + a * c + b * r;
        let (c0, c1, r0, r1) = (self.cols[p0] as f64, self.cols[p1] as f64, self.rows[q0] as f64, self.rows[q1] as f64);
        let mut res = 0.0f64;
        for blk in blocks() {
            let d = corners(blk)
                .iter()
                .map(|&(c, r)| (self.plane_at(blk.0, blk.1, c, r) - node(c, r)).abs())
                .fold(0.0, f64::max);
            res = res.max(d + self.block(blk.0, blk.1).residual as f64);
        }
        Some(([node(c0, r0), node(c1, r0), node(c0, r1)], res * (1.0 + 1e-6) + 1e-9 * (1.0 + node(c0, r0).abs())))
    }
}

impl HeightBlocks {
    /// The boxes of the blocks in each quarter of the tile (block columns and rows halved, as
    /// evenly as integers allow), row-major, empty quarters left out: each holds the fine
    /// triangles of its blocks' cells (every block's box holds those of its own), so together
    /// they hold the tile's, as `TileMesh::sub_boxes(2)` does, without a pass over its triangles.
    pub fn quarter_boxes(&self) -> Vec<([f32; 3], [f32; 3])> {
        let (nc, nr) = (self.columns(), self.rows.len() - 1);
        let halves = |n: usize| [(0, n.div_ceil(2)), (n.div_ceil(2), n)];
        let mut out = Vec::with_capacity(4);
        for (q0, q1) in halves(nr) {
            for (p0, p1) in halves(nc) {
                let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
                for b in (q0..q1).flat_map(|q| (p0..p1).map(move |p| (p, q))).map(|(p, q)| self.block(p, q)) {
                    if !b.is_empty() {
                        lo = std::array::from_fn(|a| lo[a].min(b.lo[a]));
                        hi = std::array::from_fn(|a| hi[a].max(b.hi[a]));
                    }
                }
                if lo[0] <= hi[0] {
                    out.push((lo, hi));
                }
            }
        }
        out
    }
}

/// Block boundaries along a side of `cells` cells (≥ 1): `0 = b[0] < ... < b[n] = cells`, `n` the
/// fewest blocks of at most [`BLOCK_CELLS`] cells, as even as integers allow. The same for every
/// tile side of the same length, so that the blocks of a tile row (column) line up.
pub fn bounds(cells: usize) -> Vec<usize> {
    let n = cells.div_ceil(BLOCK_CELLS).max(1);
    (0..=n).map(|p| p * cells / n).collect()
}

/// The blocks of a tile of `w` × `h` samples (≥ 2 each) whose sample (li, lj) is at `at(li, lj)`
/// (None: a hole); see the module's contract.
pub fn height_blocks(w: usize, h: usize, at: impl Fn(usize, usize) -> Option<[f32; 3]>) -> HeightBlocks {
    debug_assert!(w >= 2 && h >= 2);
    let (cols, rows) = (bounds(w - 1), bounds(h - 1));
    let mut blocks = Vec::with_capacity((cols.len() - 1) * (rows.len() - 1));
    for r in rows.windows(2) {
        for c in cols.windows(2) {
            let mut b = Block {
                lo: [f32::INFINITY; 3],
                hi: [f32::NEG_INFINITY; 3],
                complete: true,
                plane: [0.0; 3],
                residual: 0.0,
            };
            let samples = || (r[0]..=r[1]).flat_map(|lj| (c[0]..=c[1]).map(move |li| (li, lj)));
            for (li, lj) in samples() {
                match at(li, lj) {
                    Some(p) => {
                        b.lo = std::array::from_fn(|a| b.lo[a].min(p[a]));
                        b.hi = std::array::from_fn(|a| b.hi[a].max(p[a]));
                    }
                    None => b.complete = false,
                }
            }
            if !b.is_empty() {
                let local = |(li, lj): (usize, usize)| ((li - c[0]) as f64, (lj - r[0]) as f64);
                let fit = fit_plane(samples().filter_map(|s| at(s.0, s.1).map(|p| (local(s), p[2] as f64))));
                let mid = (b.lo[2] as f64 + b.hi[2] as f64) / 2.0;
                let (z0, a, bb) = fit.unwrap_or((mid, 0.0, 0.0));
                let (w, h) = ((c[1] - c[0]) as f64, (r[1] - r[0]) as f64);
                b.plane = [z0, z0 + a * w, z0 + bb * h].map(|v| v as f32);
                let [p0, p1, p2] = b.plane.map(f64::from);
                let plane = |(u, v): (f64, f64)| p0 + (p1 - p0) * u / w + (p2 - p0) * v / h;
                let res = samples()
                    .filter_map(|s| at(s.0, s.1).map(|p| (p[2] as f64 - plane(local(s))).abs()))
                    .fold(0.0f64, f64::max);
                // Rounded up, with room for the rounding of the plane's own evaluation.
                b.residual = ((res * (1.0 + 1e-6)) as f32).next_up();
            }
            blocks.push(b);
        }
    }
    let mut hb = HeightBlocks { cols, rows, blocks, whole: None };
    hb.whole = hb.node_plane((0, hb.columns()), (0, hb.rows.len() - 1));
    hb
}

/// The least-squares plane `z = z0 + a u + b v` of points `((u, v), z)`; None for fewer than 3
/// or points on a line.
fn fit_plane(points: impl Iterator<Item = ((f64, f64), f64)>) -> Option<(f64, f64, f64)> {
    let (mut m, mut rhs, mut n) = (glam::DMat3::ZERO, glam::DVec3::ZERO, 0);
    for ((u, v), z) in points {
        let row = glam::DVec3::new(1.0, u, v);
        m += glam::DMat3::from_cols(row * row.x, row * row.y, row * row.z);
        rhs += row * z;
        n += 1;
    }
    // Hadamard: a positive definite matrix's determinant is at most its diagonal's product.
    if n < 3 || m.determinant() <= 1e-9 * m.x_axis.x * m.y_axis.y * m.z_axis.z {
        return None;
    }
    let s = m.inverse() * rhs;
    s.is_finite().then_some((s.x, s.y, s.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_point_of_a_rough_block_lies_within_its_residual_of_its_plane() {
        // Random heights on 17 x 11 samples: check the bound at the samples and at points inside
        // the triangles (barycentric), where the surface is the triangles' interpolation.
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 33) as f64 / (1u64 << 31) as f64
        };
        let z: Vec<f32> =
            (0..17 * 11).map(|k| (3.0 * (k % 17) as f64 - 2.0 * (k / 17) as f64 + 5.0 * rnd()) as f32).collect();
        let at = |li: usize, lj: usize| Some([li as f32, lj as f32, z[lj * 17 + li]]);
        let hb = height_blocks(17, 11, at);
        for (k, b) in hb.blocks.iter().enumerate() {
            let (p, q) = (k % hb.columns(), k / hb.columns());
            let (c0, c1, r0, r1) = (hb.cols[p], hb.cols[p + 1], hb.rows[q], hb.rows[q + 1]);
            let [p0, p1, p2] = b.plane.map(f64::from);
            let plane = |u: f64, v: f64| {
                p0 + (p1 - p0) * (u - c0 as f64) / (c1 - c0) as f64 + (p2 - p0) * (v - r0 as f64) / (r1 - r0) as f64
            };
            for lj in r0..r1 {
                for li in c0..c1 {
                    let zz = |i: usize, j: usize| z[j * 17 + i] as f64;
                    for (s, t) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.3, 0.2), (0.9, 0.4), (0.5, 0.5)] {
                        // Lower triangle (s >= t) of the cell: (0,0), (1,0), (1,1).
                        let v =
                            zz(li, lj) + s * (zz(li + 1, lj) - zz(li, lj)) + t * (zz(li + 1, lj + 1) - zz(li + 1, lj));
                        let d = (v - plane(li as f64 + s, lj as f64 + t)).abs();
                        assert!(d <= b.residual as f64, "block {k}: {d} > {}", b.residual);
                    }
                }
            }
        }
    }

    #[test]
    fn bounds_split_a_side_into_even_blocks_of_at_most_block_cells() {
        assert_eq!(bounds(1), vec![0, 1]);
        assert_eq!(bounds(BLOCK_CELLS), vec![0, BLOCK_CELLS]);
        assert_eq!(bounds(BLOCK_CELLS + 1), vec![0, 4, 9]);
        for cells in 1..200 {
            let b = bounds(cells);
            assert_eq!((b[0], *b.last().unwrap()), (0, cells));
            assert!(b.windows(2).all(|w| w[0] < w[1] && w[1] - w[0] <= BLOCK_CELLS), "{cells}: {b:?}");
            let (lo, hi) = b.windows(2).fold((usize::MAX, 0), |(lo, hi), w| (lo.min(w[1] - w[0]), hi.max(w[1] - w[0])));
            assert!(hi - lo <= 1, "{cells}: {b:?}");
        }
    }

    #[test]
    fn a_node_plane_holds_its_blocks_surfaces() {
        // A curved surface: every sample lies within the node residual of the node plane, for
        // nodes of every size.
        let z = |li: usize, lj: usize| (0.3 * li as f64).sin() * 4.0 + 0.05 * (li * lj) as f64;
        let hb = height_blocks(30, 26, |li, lj| Some([li as f32, lj as f32, z(li, lj) as f32]));
        let (pc, qc) = (hb.columns(), hb.rows.len() - 1);
        for (p0, p1, q0, q1) in [(0, pc, 0, qc), (0, 1, 0, 1), (1, pc, 0, 2), (0, 2, 1, qc)] {
            let (plane, res) = hb.node_plane((p0, p1), (q0, q1)).unwrap();
            let (c0, r0) = (hb.cols[p0] as f64, hb.rows[q0] as f64);
            let (w, h) = (hb.cols[p1] as f64 - c0, hb.rows[q1] as f64 - r0);
            for lj in hb.rows[q0]..=hb.rows[q1] {
                for li in hb.cols[p0]..=hb.cols[p1] {
                    let v = plane[0]
                        + (plane[1] - plane[0]) * (li as f64 - c0) / w
                        + (plane[2] - plane[0]) * (lj as f64 - r0) / h;
                    assert!(
                        (z(li, lj) as f32 as f64 - v).abs() <= res,
                        "({li}, {lj}): {} > {res}",
                        (z(li, lj) - v).abs()
                    );
                }
            }
        }
        let single = hb.node_plane((1, 2), (1, 2)).unwrap();
        assert!(single.1 >= hb.block(1, 1).residual as f64);
    }

    #[test]
    fn blocks_hold_their_samples_and_know_their_holes() {
        // A plane z = x + 2y over 20 x 12 samples with a hole at sample (15, 3).
        let at =
            |li: usize, lj: usize| ((li, lj) != (15, 3)).then_some([li as f32, lj as f32, li as f32 + 2.0 * lj as f32]);
        let hb = height_blocks(20, 12, at);
        assert_eq!(hb.cols, vec![0, 6, 12, 19]);
        assert_eq!(hb.rows, vec![0, 5, 11]);
        let b = hb.block(1, 0);
        assert_eq!((b.lo, b.hi, b.complete), ([6.0, 0.0, 6.0], [12.0, 5.0, 22.0], true));
        // A plane is its own fit: heights at the corners (6, 0), (12, 0), (6, 5).
        assert_eq!(b.plane, [6.0, 12.0, 16.0]);
        assert!(b.residual < 1e-4);
        assert!(!hb.block(2, 0).complete && hb.block(2, 1).complete && hb.block(0, 1).complete);
        assert!(hb.blocks.iter().all(|b| !b.is_empty()));
        // Around the hole the fit stands on the other samples, still the plane.
        let holed = hb.block(2, 0);
        assert_eq!(holed.plane, [12.0, 19.0, 22.0]);

        let none = height_blocks(3, 3, |_, _| None);
        assert!(none.blocks[0].is_empty() && !none.blocks[0].complete);
    }
}
