//! The walk's view-independent inputs, computed on the CPU once per (isovalue, occluder depth):
//! the class of every occluder node ([`node_classes`]; [`leaf_nodes`] for single cells, with
//! their faces' classes) and the skip bricks built over them ([`brick_classes`]); and the
//! occluder boxes themselves ([`occluder_nodes`], for inspection: the walk reads the classes).
//!
//! **Skip bricks.** A brick is a block of `2^s` occluder nodes per axis. Its class is Below (or
//! Above) when every node of the brick *and of the one-node ring around it* (clipped to the grid)
//! is Below (Above), else 0 (not skippable). The walk (iso.wgsl) jumps a skippable brick whole
//! once it has entered it in that class: inside, every cell it would visit and every neighbour
//! its rounding margin would visit is of that class, so it would mark no cell, meet no class
//! change and no NaN (see the argument in `super::render`). NaN nodes never make a brick
//! skippable (the walk marks NaN cells: they may hold surface when occluders are coarser than
//! the march cells).

use rayon::prelude::*;

use super::octree::{classify_range, Class, MinMaxOctree, NodeInfo};

impl MinMaxOctree {
    /// The map pass's class and low faces of every single cell at isovalue `w` (`leaf_nodes`),
    /// straight from the samples; `None` when the leaves are stored levels or the volume is lazy
    /// (then use [`MinMaxOctree::map_at_depth`]: a lazy volume's classes come from the stored
    /// levels, where this would read every sample).
    pub fn leaf_nodes(&self, w: f32) -> Option<Vec<u8>> {
        self.leaves_from_samples().then(|| {
            let (values, samples) = self.all_samples();
            leaf_nodes(&values, samples, w)
        })
    }

    /// The walk's contour bricks (`contour_bricks`) with a block for each of `bricks`, the
    /// nodes 2 levels above the cells that straddle the isovalue: a brick with a passable cell has
    /// samples on both sides of it or at it, so its node straddles. (At most 4 cells per axis: the
    /// root, brick 0.) A lazy volume has no leaf classes, so no contours: correct, but reads all.
    pub fn contour_bricks(&self, bricks: &[NodeInfo]) -> (Vec<u32>, usize) {
        let blocks: Vec<[u32; 3]> = bricks.iter().map(|n| [n.ix, n.iy, n.iz]).collect();
        let (values, samples) = self.all_samples();
        contour_bricks(&values, samples, &blocks)
    }
}

/// Node classes of the map pass (iso.wgsl).
pub(super) const CLASS_PASS: u8 = 0;
pub(super) const CLASS_BELOW: u8 = 1;
pub(super) const CLASS_ABOVE: u8 = 2;
pub(super) const CLASS_NAN: u8 = 3;

/// Bricks of the fine skip level: `2^FINE_SHIFT` occluder nodes per axis.
pub(super) const FINE_SHIFT: u32 = 2;
/// Bricks of the coarse skip level: `2^COARSE_SHIFT` occluder nodes per axis.
pub(super) const COARSE_SHIFT: u32 = 4;
/// Bricks of the host walk's third skip level: `2^HUGE_SHIFT` occluder nodes per axis
/// ([`pack_nodes`] with `huge`).
pub(super) const HUGE_SHIFT: u32 = 6;

/// One level of skip bricks ([`brick_classes`]): a byte per brick (x fastest), and the bricks
/// per axis.
pub type BrickLevel = (Vec<u8>, [u32; 3]);

/// The classes of the nodes at `depth` (x fastest, then y, z) for the map pass: Below / Above
/// (NaN-free by [`classify_range`]), NaN (any NaN sample: outside the domain), else passable.
/// Single cells (`depth == tree.max_depth()`) go through [`leaf_nodes`], the same classes
/// straight from the samples.
pub fn node_classes(tree: &MinMaxOctree, w: f32, depth: u32) -> Vec<u8> {
    if depth == tree.max_depth() {
        if let Some(mut c) = tree.leaf_nodes(w) {
            c.iter_mut().for_each(|k| *k &= 3);
            return c;
        }
    }
    tree.map_at_depth(depth, |min, max, nan| match classify_range(min, max, w) {
        _ if nan => CLASS_NAN,
        Class::Below => CLASS_BELOW,
        Class::Above => CLASS_ABOVE,
        _ => CLASS_PASS,
    })
}

/// The occluders of depth `depth`: maximal Below and Above nodes of depth <= `depth` (see
/// `super::render`'s module docs). Returned in octree order (deterministic).
#[cfg(test)]
pub fn occluder_nodes(tree: &MinMaxOctree, w: f32, depth: u32) -> (Vec<NodeInfo>, Vec<NodeInfo>) {
    let depth = depth.min(tree.max_depth());
    let (mut below, mut above) = (Vec::new(), Vec::new());
    let mut frontier = vec![tree.root()];
    for d in 0..=depth {
        let (b, a, next): (Vec<NodeInfo>, Vec<NodeInfo>, Vec<NodeInfo>) = frontier
            .par_iter()
            .fold(
                || (Vec::new(), Vec::new(), Vec::new()),
                |(mut b, mut a, mut nx), n| {
                    match n.classify(w) {
                        Class::Below => b.push(*n),
                        Class::Above => a.push(*n),
                        Class::Straddles if d < depth => nx.extend(tree.children(n)),
                        _ => {}
                    }
                    (b, a, nx)
                },
            )
            .reduce(
                || (Vec::new(), Vec::new(), Vec::new()),
                |(mut b0, mut a0, mut n0), (b1, a1, n1)| {
                    b0.extend(b1);
                    a0.extend(a1);
                    n0.extend(n1);
                    (b0, a0, n0)
                },
            );
        below.extend(b);
        above.extend(a);
        frontier = next;
    }
    (below, above)
}

/// The class and the low faces of every cell of a volume with `samples` samples per axis (x
/// fastest), one byte per cell as the walk reads it (iso.wgsl `node_info`, without the skip
/// bricks' bits 2-3, which [`pack_nodes`] adds):
/// - bits 0-1, the class from the cell's 8 corners: NaN when one is NaN, Below when all are `< w`,
///   Above when all are `> w`, else passable (what [`node_classes`] gives at the leaves);
/// - bits 4, 5, 6: the cell's low x, y, z face (the face at its lowest x, y, z) is uniform, its 4
///   corners all `< w` or all `> w`; bit 7: the cell's low corner (on all three faces) is `< w`,
///   so a uniform face is Below or Above by that corner. A face whose corners are all on one side
///   has no crossing edge, so no marching-cubes triangle touches it: the whole face lies on that
///   side of the surface, as a Below / Above cell does (the walk's finer occluders, see
///   `super::render`). Corners that are NaN or equal to `w` make no face uniform.
///
/// One pass over the samples, in slabs of a few layers of cells: each sample is coded once per
/// slab (and the codes of two sample layers stay in cache), where the class and the faces used to
/// be two passes coding each sample eight times.
pub fn leaf_nodes(values: &[f32], samples: [usize; 3], w: f32) -> Vec<u8> {
    let [nx, ny, _] = samples;
    let (cx, cy, cz) = (nx - 1, ny - 1, samples[2] - 1);
    // Per sample: bit 0 below, bit 1 above, bit 2 NaN (a NaN is neither below nor above).
    let code = |v: f32| (v < w) as u8 | ((v > w) as u8) << 1 | (v.is_nan() as u8) << 2;
    let coded = |z: usize, out: &mut [u8]| {
        // Eight samples at a time (the compiler keeps these in SIMD lanes; the plain loop it
        // compiled to scalar compares here), then the rest.
        let (mut o8, mut v8) = (out.chunks_exact_mut(8), values[z * nx * ny..][..nx * ny].chunks_exact(8));
        for (o, v) in (&mut o8).zip(&mut v8) {
            for i in 0..8 {
                o[i] = code(v[i]);
            }
        }
        for (o, &v) in o8.into_remainder().iter_mut().zip(v8.remainder()) {
            *o = code(v);
        }
    };
    const SLAB: usize = 4;
    let mut out = vec![0u8; cx * cy * cz];
    out.par_chunks_mut(cx * cy * SLAB).enumerate().for_each(|(slab, cells)| {
        // The codes of the sample layers below and above the layer of cells.
        let (mut lo, mut hi) = (vec![0u8; nx * ny], vec![0u8; nx * ny]);
        let mut cols = vec![0u32; nx];
        coded(slab * SLAB, &mut lo);
        for (dk, layer) in cells.chunks_mut(cx * cy).enumerate() {
            coded(slab * SLAB + dk + 1, &mut hi);
            for (j, row_out) in layer.chunks_mut(cx).enumerate() {
                // The sample rows (k, j), (k, j + 1), (k + 1, j), (k + 1, j + 1) around the row.
                let (c0, c1) = (&lo[j * nx..][..nx], &lo[(j + 1) * nx..][..nx]);
                let (c2, c3) = (&hi[j * nx..][..nx], &hi[(j + 1) * nx..][..nx]);
                // Per column of 4 samples (x): byte 0 the AND of their codes (the low x face of
                // the cell at x), byte 1 that of the samples at y = j, byte 2 at z = k, bits
                // 24-26 the OR, bit 31 the below bit of the sample (x, j, k); a cell combines two
                // columns. (Zipped slices of one length: no bounds checks; the loops vectorise.)
                let quads = c0.iter().zip(c1).zip(c2.iter().zip(c3));
                for (col, ((&a, &b), (&c, &d))) in cols.iter_mut().zip(quads) {
                    let (a, b, c, d) = (a as u32, b as u32, c as u32, d as u32);
                    *col = (a & b & c & d) | (a & c) << 8 | (a & b) << 16 | (a | b | c | d) << 24 | (a & 1) << 31;
                }
                // Faces: x = (x, j..j+1, k..k+1); y = (x..x+1, j, k..k+1); z = (x..x+1,
                // j..j+1, k). A NaN's code has neither bit 0 nor 1: the AND of a cell with one
                // is 0 there.
                let some = |v: u32| (v | v >> 1) & 1;
                for ((o, &l), &h) in row_out.iter_mut().zip(&cols[..cx]).zip(&cols[1..]) {
                    let and = l & h;
                    let nan = ((l | h) >> 26) & 1;
                    let class = (and & 3) | (nan * 3);
                    let faces = some(l & 3) | some(and >> 8 & 3) << 1 | some(and >> 16 & 3) << 2 | (l >> 31) << 3;
                    *o = (class | faces << 4) as u8;
                }
            }
            std::mem::swap(&mut lo, &mut hi);
        }
    });
    out
}

/// Makes every node of `classes` (dims `dims`, x fastest; the class in bits 0-1, the other bits
/// are kept) that shares a face, an edge or a corner
/// with a NaN node NaN too, for the walk: the surface has a boundary on the faces of NaN nodes,
/// and a ray that passes within rounding distance of that boundary may be drawn past it, so a
/// proof (a segment from one side of the surface to the other) must keep a node away from NaN.
/// (Found by the random-volume test: a ray 0.0003 cells inside a face bordering NaN cells
/// crossed the surface next to its boundary edge; the rasteriser put the pixel beyond the edge.)
/// Returns how many nodes became NaN.
pub fn dilate_nan(classes: &mut [u8], dims: [u32; 3]) -> usize {
    let d = dims.map(|v| v as usize);
    let nan = |k: u8| k & 3 == CLASS_NAN;
    // (A fold rather than `any`, which stops early but does not vectorise.)
    if !classes.par_chunks(1 << 16).any(|c| c.iter().fold(false, |a, &k| a | nan(k))) {
        return 0;
    }
    // Separable: a node is within one node of a NaN node (26-neighbourhood) iff it is along x of
    // a node within one along y of a node within one along z of one.
    let mut m: Vec<bool> = classes.par_iter().map(|&k| nan(k)).collect();
    let strides = [1, d[0], d[0] * d[1]];
    for (a, &st) in strides.iter().enumerate() {
        let src = m.clone();
        m.par_iter_mut().enumerate().for_each(|(i, v)| {
            let p = i / st % d[a];
            *v = src[i] || (p > 0 && src[i - st]) || (p + 1 < d[a] && src[i + st]);
        });
    }
    let mut n = 0;
    for (k, &to_nan) in classes.iter_mut().zip(&m) {
        if to_nan && !nan(*k) {
            *k |= CLASS_NAN;
            n += 1;
        }
    }
    n
}

/// Contour bricks (iso.wgsl `face_side`): `2^CONTOUR_SHIFT` cells per axis.
pub(super) const CONTOUR_SHIFT: u32 = 2;
/// A contour brick's block of samples: `CONTOUR_SAMPLES`³ (its cells' corners).
pub(super) const CONTOUR_SAMPLES: usize = (1 << CONTOUR_SHIFT) + 1;
/// A contour brick without samples.
pub(super) const NO_BLOCK: u32 = u32::MAX;

/// The contour bricks per axis of a volume with `samples` samples per axis: its cells in bricks
/// of `2^CONTOUR_SHIFT`, the last one per axis partial (the table of [`contour_bricks`], x fastest).
pub(super) fn contour_grid(samples: [usize; 3]) -> [usize; 3] {
    samples.map(|n| (n - 1).div_ceil(1 << CONTOUR_SHIFT))
}

/// The samples the walk reads to place the contour of each face it crosses (iso.wgsl
/// `face_side`), for a volume of `samples` samples per axis: per brick of 4³ cells (x fastest) one
/// word, the index of its block of 5³ samples (its cells' corners, x fastest, as f32 bits; past
/// the volume's end the last sample repeats) or [`NO_BLOCK`]; then the blocks, in the order of
/// `blocks` (brick coordinates, each once). The walk needs the block of every brick holding a
/// passable cell (the faces of Below / Above cells are uniform, their class bits settle them; a
/// NaN cell resets the walk): the straddling nodes 2 levels above the cells are those bricks and
/// a few more ([`MinMaxOctree::contour_bricks`](super::MinMaxOctree::contour_bricks)). Returns
/// the words and the number of bricks (where the blocks start). Surface bricks only: the frog
/// tissues' 32 M samples need 19 MB instead of 128.
pub fn contour_bricks(values: &[f32], samples: [usize; 3], blocks: &[[u32; 3]]) -> (Vec<u32>, usize) {
    let [nx, ny, _] = samples;
    let b = 1usize << CONTOUR_SHIFT;
    let bd = contour_grid(samples);
    let nb = bd[0] * bd[1] * bd[2];
    let n = CONTOUR_SAMPLES;
    let mut words = vec![NO_BLOCK; nb + blocks.len() * n * n * n];
    let (table, data) = words.split_at_mut(nb);
    for (slot, p) in blocks.iter().enumerate() {
        table[(p[2] as usize * bd[1] + p[1] as usize) * bd[0] + p[0] as usize] = slot as u32;
    }
    data.par_chunks_mut(n * n * n).zip(blocks).for_each(|(out, p)| {
        let o = p.map(|v| v as usize * b);
        // Row by row (x fastest), each sample index clamped to the volume.
        for (r, row) in out.chunks_exact_mut(n).enumerate() {
            let [y, z] = [(o[1] + r % n).min(ny - 1), (o[2] + r / n).min(samples[2] - 1)];
            let src = &values[(z * ny + y) * nx..][..nx];
            for (i, w) in row.iter_mut().enumerate() {
                *w = src[(o[0] + i).min(nx - 1)].to_bits();
            }
        }
    });
    (words, nb)
}

/// ORs `src` into `dst`.
fn or_into(dst: &mut [u8], src: &[u8]) {
    dst.iter_mut().zip(src).for_each(|(a, &b)| *a |= b);
}

/// Reduces `v` (dims `d`, x fastest) along `axis` to blocks of `b` entries, each widened by
/// `ring` entries on both sides (clipped): the OR of the block's entries, each taken as
/// `bit(entry)`.
fn reduce_axis(
    v: &[u8],
    d: [usize; 3],
    axis: usize,
    b: usize,
    ring: usize,
    bit: impl Fn(u8) -> u8 + Sync,
) -> (Vec<u8>, [usize; 3]) {
    let mut od = d;
    od[axis] = d[axis].div_ceil(b);
    let range = |bi: usize| (bi * b).saturating_sub(ring)..(bi * b + b + ring).min(d[axis]);
    let mut out = vec![0u8; od[0] * od[1] * od[2]];
    let row = |y: usize, z: usize| &v[(z * d[1] + y) * d[0]..][..d[0]];
    // One output row (along x) at a time.
    out.par_chunks_mut(od[0]).enumerate().for_each_init(
        || (Vec::new(), Vec::new()),
        |(m, wide), (i, o)| {
            let (y, z) = (i % od[1], i / od[1]);
            match axis {
                0 => {
                    // Along x in whole-row passes (a brick at a time runs a short loop per brick):
                    // the row's bits, widened by the ring (each entry ORed with its neighbours),
                    // then ORed over each brick's run.
                    m.clear();
                    m.extend(row(y, z).iter().map(|&k| bit(k)));
                    for _ in 0..ring {
                        wide.clear();
                        wide.extend_from_slice(m);
                        let n = m.len();
                        or_into(&mut wide[1..], &m[..n - 1]);
                        or_into(&mut wide[..n - 1], &m[1..]);
                        std::mem::swap(m, wide);
                    }
                    let or = |run: &[u8]| run.iter().fold(0, |a, &k| a | k);
                    if b == 4 {
                        let (quads, tail) = m.as_chunks::<4>();
                        o.iter_mut().zip(quads).for_each(|(o, q)| *o = q[0] | q[1] | q[2] | q[3]);
                        if !tail.is_empty() {
                            o[quads.len()] = or(tail);
                        }
                    } else {
                        o.iter_mut().zip(m.chunks(b)).for_each(|(o, run)| *o = or(run));
                    }
                }
                1 => range(y).for_each(|y| o.iter_mut().zip(row(y, z)).for_each(|(a, &k)| *a |= bit(k))),
                _ => range(z).for_each(|z| o.iter_mut().zip(row(y, z)).for_each(|(a, &k)| *a |= bit(k))),
            }
        },
    );
    (out, od)
}

/// Reduces `v` (dims `d`) to blocks of `b`³ widened by `ring`: the OR of `bit(entry)` over each
/// block (see [`reduce_axis`]).
fn reduce(
    v: &[u8],
    d: [usize; 3],
    b: usize,
    ring: usize,
    bit: impl Fn(u8) -> u8 + Sync + Copy,
) -> (Vec<u8>, [usize; 3]) {
    let (x, dx) = reduce_axis(v, d, 0, b, ring, bit);
    let (y, dy) = reduce_axis(&x, dx, 1, b, ring, |k| k);
    reduce_axis(&y, dy, 2, b, ring, |k| k)
}

/// The skip bricks of the class grid `classes` (dims `dims`; the class in bits 0-1, the other
/// bits ignored) at one level per shift of `shifts` (increasing): bricks of `2^shift` nodes per
/// axis, each Below / Above when it and its one-node ring are all of that class, else 0. Returns
/// the grids (x fastest) and their dims, one per shift. Each level after the first is reduced
/// from the one before, not from the nodes: a brick's ring is the union of its sub-bricks' rings.
pub fn brick_classes(classes: &[u8], dims: [u32; 3], shifts: &[u32]) -> Vec<BrickLevel> {
    let class = |v: &[u8]| -> Vec<u8> {
        let (below, above) = (1 << CLASS_BELOW, 1 << CLASS_ABOVE);
        v.par_iter()
            .map(|&m| {
                if m == below {
                    CLASS_BELOW
                } else if m == above {
                    CLASS_ABOVE
                } else {
                    0
                }
            })
            .collect()
    };
    // The classes present in each brick, as a bitmask (bit k: class k): separable, an OR.
    let mut level: Option<(Vec<u8>, [usize; 3], u32)> = None;
    let mut out = Vec::with_capacity(shifts.len());
    for &s in shifts {
        let (m, md) = match &level {
            None => reduce(classes, dims.map(|v| v as usize), 1 << s, 1, |k| 1 << (k & 3)),
            Some((prev, pd, ps)) => reduce(prev, *pd, 1 << (s - ps), 0, |k| k),
        };
        out.push((class(&m), md.map(|v| v as u32)));
        level = Some((m, md, s));
    }
    out
}

/// The nodes as the walk reads them (iso.wgsl `node_info`), from `nodes` (dims `dims`, x
/// fastest), one byte per node with its class in bits 0-1, bits 2-3 clear, and its low faces in
/// bits 4-7 ([`leaf_nodes`]: single-cell nodes only; 0 without); this sets bit 2 when the node's
/// fine skip brick (`2^FINE_SHIFT` nodes per axis, [`brick_classes`]) is skippable, bit 3 when
/// its coarse brick is too (a skippable brick's class is that of each of its nodes).
///
/// **Layout: bricks of 4³ nodes**, one 64-byte cache line each (x fastest inside, bricks x
/// fastest, the grid padded with zeros to whole bricks; [`brick_index`]). A ray steps to a
/// neighbouring node, which a linear layout puts a row or a slice (up to hundreds of KB) away: on
/// a CPU rasteriser each lane's read then missed the caches (the walk's hottest instruction on
/// the frog's 32 MB grid); in bricks most steps stay in a line already read.
///
/// With `huge`, also returns the third level of skip bricks (`2^HUGE_SHIFT` nodes per axis,
/// [`brick_classes`]), which only the host's walk reads: a ray in empty space jumps up to 64
/// cells at once where the coarse level stops every 16 (on the frog most of the walk's steps are
/// jumps). It is reduced from the coarse level's bricks.
///
/// With `huge` (the host's walk), also returns the skip table, [`skip_byte`] per brick (else empty), made
/// from each row of bricks right after it is written, while it is in the caches: a pass over the
/// whole grid afterwards read the frog's 32 MB again (12 ms of its cold frame).
pub(super) fn pack_nodes(nodes: &[u8], dims: [u32; 3], huge: bool) -> (Vec<u8>, Vec<u8>, Option<BrickLevel>) {
    let shifts = [FINE_SHIFT, COARSE_SHIFT, HUGE_SHIFT];
    let mut levels = brick_classes(nodes, dims, &shifts[..if huge { 3 } else { 2 }]).into_iter();
    let (fine, fd) = levels.next().expect("the fine level");
    let (coarse, cd) = levels.next().expect("the coarse level");
    let huge = levels.next();
    let [nx, ny, nz] = dims.map(|v| v as usize);
    let nb = dims.map(|v| v.div_ceil(4) as usize);
    let mut out = vec![0u8; nb[0] * nb[1] * nb[2] * 64];
    let mut skip = vec![0u8; if huge.is_some() { nb[0] * nb[1] * nb[2] } else { 0 }];
    // (Empty without the table: one empty chunk per row of bricks.)
    let skip_rows = skip.chunks_mut(nb[0].max(1)).map(Some).chain(std::iter::repeat_with(|| None));
    let rows: Vec<_> = out.chunks_mut(nb[0] * 64).zip(skip_rows).collect();
    // One row of bricks (along x) at a time: 4 x 4 rows of nodes, each in runs of 4 (a fine
    // skip brick's run: FINE_SHIFT = 2, the same 4 nodes as a brick's row).
    rows.into_par_iter().enumerate().for_each(|(r, (bricks, skip))| {
        let (by, bz) = (r % nb[1], r / nb[1]);
        for (z, y) in (4 * bz..(4 * bz + 4).min(nz)).flat_map(|z| (4 * by..(4 * by + 4).min(ny)).map(move |y| (z, y))) {
            let start = |bd: [u32; 3], s: u32| ((z >> s) * bd[1] as usize + (y >> s)) * bd[0] as usize;
            let f = &fine[start(fd, FINE_SHIFT)..][..fd[0] as usize];
            let c = &coarse[start(cd, COARSE_SHIFT)..][..cd[0] as usize];
            let row = &nodes[(z * ny + y) * nx..][..nx];
            let at = (z % 4) * 16 + (y % 4) * 4;
            for (b, run) in row.chunks(1 << FINE_SHIFT).enumerate() {
                let fs = f[b] != 0;
                let cs = fs && c[b >> (COARSE_SHIFT - FINE_SHIFT)] != 0;
                let bits = (fs as u8) << 2 | (cs as u8) << 3;
                let dst = &mut bricks[b * 64 + at..][..run.len()];
                dst.iter_mut().zip(run).for_each(|(o, &k)| *o = k | bits);
            }
        }
        if let Some(skip) = skip {
            skip.iter_mut().zip(bricks.chunks(64)).for_each(|(s, b)| *s = skip_byte(b));
        }
    });
    (out, skip, huge)
}

/// The skip table's entry of one brick of [`pack_nodes`]' output (its 64 bytes, 4³ nodes): the
/// byte all its nodes hold when it is a skippable fine brick (bit 2 set; every node then holds the
/// same byte: the brick's class, its skip flags and, for single cells, faces all uniform on the
/// class's side), else 0. The host's walk reads a node of a skippable brick from this table (one
/// byte per brick, [`pack_nodes`] with `huge`), which stays in the caches where the nodes (32 MB
/// on the frog) do not. (Requires the fine skip bricks to be the storage bricks: `FINE_SHIFT` = 2.)
pub(super) fn skip_byte(b: &[u8]) -> u8 {
    const _: () = assert!(FINE_SHIFT == 2);
    if b[0] & 4 != 0 && b.iter().all(|&v| v == b[0]) {
        b[0]
    } else {
        0
    }
}

/// The most [`skip_reach`] gives: a box of up to 29 bricks per axis (116 nodes).
pub(super) const REACH_CAP: u8 = 15;

/// Per brick of the skip table ([`skip_byte`]; `bdims` bricks per axis, x fastest), how far skippable bricks
/// of its class reach about it: the largest `r` (at most [`REACH_CAP`]) such that every brick of
/// the grid within `r - 1` bricks of it (Chebyshev distance) is a skippable brick of its class, 0
/// where it is not skippable. The host's walk jumps such a box of `2 r - 1` bricks per axis whole:
/// the ring of the box lies in the rings of its bricks, so it is of the class too.
///
/// A cube is the sum of three segments, so the reach is found an axis at a time: with `f` the
/// reach over the axes done so far, the reach over one more is `min over d of max(|d|, f(p + d e))`
/// (`f` counting 0 at a brick of another class, the grid's outside not counting): a brick `d` away
/// bounds the reach to `|d|` unless its own reach is larger. Rows and slices at a time, so the
/// compiler vectorises the bytes.
pub(super) fn skip_reach(skip: &[u8], bdims: [u32; 3]) -> Vec<u8> {
    let [nx, ny, _] = bdims.map(|v| v as usize);
    // The class of a skippable brick (1 or 2), 0 for the others.
    let cls: Vec<u8> = skip.iter().map(|&b| if b == 0 { 0 } else { b & 3 }).collect();
    // `o` bounded by the bricks `f` (classes `cn`) `d` away from those of classes `c`.
    let bound = |o: &mut [u8], c: &[u8], f: &[u8], cn: &[u8], d: u8| {
        for (((o, &c), &f), &cn) in o.iter_mut().zip(c).zip(f).zip(cn) {
            *o = (*o).min((if c == cn { f } else { 0 }).max(d));
        }
    };
    let f: Vec<u8> = cls.iter().map(|&k| if k == 0 { 0 } else { REACH_CAP }).collect();
    // Along x, row by row.
    let mut fx = f.clone();
    fx.par_chunks_mut(nx).zip(f.par_chunks(nx)).zip(cls.par_chunks(nx)).for_each(|((o, f), c)| {
        for d in 1..(REACH_CAP as usize).min(nx) {
            bound(&mut o[d..], &c[d..], &f[..nx - d], &c[..nx - d], d as u8);
            bound(&mut o[..nx - d], &c[..nx - d], &f[d..], &c[d..], d as u8);
        }
    });
    // Along y (rows of a slice) and z (slices): whole rows / slices at a time.
    let along = |f: &[u8], part: usize, len: usize| -> Vec<u8> {
        let mut out = f.to_vec();
        out.par_chunks_mut(part).enumerate().for_each(|(i, o)| {
            let at = i % len;
            let own = &cls[i * part..(i + 1) * part];
            for d in 1..(REACH_CAP as usize).min(len) {
                for j in [at.checked_sub(d).map(|_| i - d), (at + d < len).then_some(i + d)].into_iter().flatten() {
                    bound(o, own, &f[j * part..(j + 1) * part], &cls[j * part..(j + 1) * part], d as u8);
                }
            }
        });
        out
    };
    let fy = along(&fx, nx, ny);
    along(&fy, nx * ny, bdims[2] as usize)
}

/// Where [`pack_nodes`] puts node `p` of a grid of `dims` nodes: brick `p / 4` (x fastest over
/// `ceil(dims / 4)` bricks), 64 bytes each, node `p % 4` inside (x fastest). (iso.wgsl
/// `node_info` computes the same; the host's walk calls this.)
#[inline]
pub(super) fn brick_index(dims: [u32; 3], p: [u32; 3]) -> usize {
    let nb = dims.map(|v| v.div_ceil(4) as usize);
    let [b, l] = [p.map(|v| (v / 4) as usize), p.map(|v| (v % 4) as usize)];
    ((b[2] * nb[1] + b[1]) * nb[0] + b[0]) * 64 + l[2] * 16 + l[1] * 4 + l[0]
}

/// Packs the 2-bit values in bits 0-1 of `v` (the other bits ignored) 16 to a little-endian u32
/// word (value `i` in bits `2 (i % 16)` of word `i / 16`).
pub(super) fn pack2(v: &[u8]) -> Vec<u32> {
    // 8 values at a time: their bytes masked to 2 bits, then gathered pairwise into 16 bits.
    let gather8 = |b: &[u8]| {
        let mut x = u64::from_le_bytes(b.try_into().unwrap()) & 0x0303_0303_0303_0303;
        x = (x | x >> 6) & 0x000f_000f_000f_000f;
        x = (x | x >> 12) & 0x0000_00ff_0000_00ff;
        ((x | x >> 24) & 0xffff) as u32
    };
    let mut out = vec![0u32; v.len().div_ceil(16)];
    out.par_chunks_mut(1 << 12).zip(v.par_chunks(16 << 12)).for_each(|(o, c)| {
        let mut words = c.chunks_exact(16);
        for (w, s) in o.iter_mut().zip(&mut words) {
            *w = gather8(&s[..8]) | gather8(&s[8..]) << 16;
        }
        if let Some(w) = o.get_mut(c.len() / 16) {
            *w = words.remainder().iter().enumerate().fold(0u32, |w, (i, &k)| w | (k as u32 & 3) << (2 * i));
        }
    });
    out
}

/// How many of the classes packed by [`pack2`] are Below, Above and NaN, in that order (the
/// padding of the last word reads as passable, `CLASS_PASS` = 0): a population count per word
/// instead of three comparisons per node byte.
pub(super) fn class_counts(words: &[u32]) -> [u32; 3] {
    const _: () = assert!(CLASS_PASS == 0 && CLASS_BELOW == 1 && CLASS_ABOVE == 2 && CLASS_NAN == 3);
    let count = |c: &[u32]| {
        c.iter().fold([0u32; 3], |[b, a, n], &w| {
            let (lo, hi) = (w & 0x5555_5555, w >> 1 & 0x5555_5555);
            [b + (lo & !hi).count_ones(), a + (hi & !lo).count_ones(), n + (lo & hi).count_ones()]
        })
    };
    words.par_chunks(1 << 14).map(count).reduce(|| [0; 3], |x, y| [0, 1, 2].map(|i| x[i] + y[i]))
}

/// The class (`CLASS_*`) of node `p` of the classes packed by [`pack2`] (grid `dims`).
pub(super) fn node_class(classes: &[u32], dims: [u32; 3], p: [u32; 3]) -> u8 {
    let i = ((p[2] * dims[1] + p[1]) * dims[0] + p[0]) as usize;
    (classes[i / 16] >> (2 * (i % 16)) & 3) as u8
}

#[cfg(test)]
mod tests;

/// The walk with skip bricks against the walk cell by cell and against no culling, on the GPU.
#[cfg(test)]
mod walk_tests;
