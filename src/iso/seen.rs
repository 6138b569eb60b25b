//! The walk's output on the CPU (iso.wgsl `cs_map` marks, [`super::passes::march`] reads them
//! back): which march cells are seen ([`seen_cells`]), how many of a node's cells are
//! ([`cells_seen`]: the node is visible when any is) and which of a patch's triangles lie in them
//! ([`visible_ranges`]).

use rayon::prelude::*;

use super::bricks::{node_class, CLASS_NAN, CLASS_PASS};
use super::march::SurfacePatch;
use super::octree::NodeInfo;

/// How many march cells of node `n` are set in `bits` (grid `mdims`, a volume cell `c` is march
/// cell `c >> shift`; `n` is at the march depth or coarser).
pub(super) fn cells_seen(n: &NodeInfo, bits: &[u32], mdims: [u32; 3], shift: u32) -> u32 {
    let r = |a: usize| (n.cell_lo[a] >> shift)..((n.cell_hi[a] + (1 << shift) - 1) >> shift);
    let mut seen = 0;
    for k in r(2) {
        for j in r(1) {
            for i in r(0) {
                let m = ((k * mdims[1] + j) * mdims[0] + i) as usize;
                seen += bits[m / 32] >> (m % 32) & 1;
            }
        }
    }
    seen
}

/// The march cells seen, one bit each (cell `i` is bit `i % 32` of word `i / 32`), from the walk's
/// 4-bit `marks` (`passes::march`): a cell is seen when a ray entered it and it may hold surface
/// (bit 0), or when it may hold surface and lies across the planes of a near event of a
/// neighbour (bits 1-3: a ray entered that neighbour within the walk's margin of its faces across
/// x, y or z, so rounding may have skipped the cells beyond them): every cell at offsets of -1 or
/// +1 along a non-empty subset of the near axes. The walk used to mark exactly the cells on the
/// near side with up to seven class reads and atomics per step; a CPU rasteriser runs that code
/// for every lane at every step whether any lane needs it or not (40 % of the walk on the Pesco
/// field). Both sides are a superset: a cell more can only draw a triangle more.
/// `nodes`: the occluder nodes' classes ([`pack2`](super::bricks::pack2), grid `occ_dims`); `occ_shift`: march depth
/// - occluder depth (a march cell's node is its index `>> occ_shift`).
pub(super) fn seen_cells(
    marks: &[u32],
    mdims: [u32; 3],
    nodes: &[u32],
    occ_dims: [u32; 3],
    occ_shift: u32,
) -> Vec<u32> {
    use std::sync::atomic::{AtomicU32, Ordering};
    let n = mdims.iter().map(|&v| v as usize).product::<usize>();
    let bits: Vec<AtomicU32> = (0..n.div_ceil(32))
        .into_par_iter()
        .map(|w| {
            // Bits 0, 4, ..., 28 of each word gathered into 8 contiguous bits.
            let gather = |m: u32| {
                let x = m & 0x1111_1111;
                let x = (x | x >> 3) & 0x0303_0303;
                let x = (x | x >> 6) & 0x000f_000f;
                (x | x >> 12) & 0xff
            };
            let words = &marks[4 * w..(4 * w + 4).min(marks.len())];
            AtomicU32::new(words.iter().enumerate().fold(0, |out, (part, &m)| out | gather(m) << (8 * part)))
        })
        .collect();
    let may_hold = |x: u32, y: u32, z: u32| {
        let k = node_class(nodes, occ_dims, [x, y, z].map(|v| v >> occ_shift));
        k == CLASS_PASS || k == CLASS_NAN
    };
    marks.par_iter().enumerate().filter(|(_, &m)| m & 0xeeee_eeee != 0).for_each(|(w, &m)| {
        for i in 0..8 {
            let near = m >> (4 * i + 1) & 7;
            if near == 0 {
                continue;
            }
            let cell = (8 * w + i) as u32;
            let p = [cell % mdims[0], cell / mdims[0] % mdims[1], cell / (mdims[0] * mdims[1])];
            // Offsets -1, 0, +1 along the near axes (0 only along the others), the cell itself excluded.
            let range = |a: usize| -> std::ops::RangeInclusive<i64> {
                if near >> a & 1 == 1 {
                    -1..=1
                } else {
                    0..=0
                }
            };
            for dz in range(2) {
                for dy in range(1) {
                    for dx in range(0) {
                        let q = [p[0] as i64 + dx, p[1] as i64 + dy, p[2] as i64 + dz];
                        if (dx, dy, dz) == (0, 0, 0) || (0..3).any(|a| q[a] < 0 || q[a] >= mdims[a] as i64) {
                            continue;
                        }
                        let q = q.map(|v| v as u32);
                        let j = ((q[2] * mdims[1] + q[1]) * mdims[0] + q[0]) as usize;
                        let b = 1u32 << (j % 32);
                        if bits[j / 32].load(Ordering::Relaxed) & b == 0 && may_hold(q[0], q[1], q[2]) {
                            bits[j / 32].fetch_or(b, Ordering::Relaxed);
                        }
                    }
                }
            }
        }
    });
    bits.into_iter().map(AtomicU32::into_inner).collect()
}

/// The triangle ranges of `p` (the patch of node `n`) that lie in march cells set in `bits`
/// (grid `mdims`, a volume cell `c` is march cell `c >> shift`), consecutive cells merged.
pub(super) fn visible_ranges(
    p: &SurfacePatch,
    n: &NodeInfo,
    bits: &[u32],
    mdims: [u32; 3],
    shift: u32,
) -> Vec<[u32; 2]> {
    let mut out: Vec<[u32; 2]> = Vec::new();
    if p.cell_starts.is_empty() {
        return out;
    }
    let (lo, hi) = (n.cell_lo, n.cell_hi);
    let mut c = 0usize;
    for k in lo[2]..hi[2] {
        for j in lo[1]..hi[1] {
            for i in lo[0]..hi[0] {
                let (a, b) = (p.cell_starts[c], p.cell_starts[c + 1]);
                c += 1;
                if a == b {
                    continue;
                }
                let m = (((k >> shift) * mdims[1] + (j >> shift)) * mdims[0] + (i >> shift)) as usize;
                if bits[m / 32] >> (m % 32) & 1 == 1 {
                    match out.last_mut() {
                        Some(r) if r[1] == a => r[1] = b,
                        _ => out.push([a, b]),
                    }
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::iso::bricks::{pack2, CLASS_ABOVE, CLASS_BELOW};

    /// Marks of a `d` grid with `(cell, 4-bit mark)` set.
    fn marks(d: [u32; 3], set: &[([u32; 3], u32)]) -> Vec<u32> {
        let mut m = vec![0u32; (d.iter().product::<u32>() as usize).div_ceil(8)];
        for &(c, b) in set {
            let i = ((c[2] * d[1] + c[1]) * d[0] + c[0]) as usize;
            m[i / 8] |= b << (4 * (i % 8));
        }
        m
    }

    fn cells(bits: &[u32], d: [u32; 3]) -> Vec<[u32; 3]> {
        let n = d.iter().product::<u32>();
        (0..n)
            .filter(|&i| bits[i as usize / 32] >> (i % 32) & 1 == 1)
            .map(|i| [i % d[0], i / d[0] % d[1], i / (d[0] * d[1])])
            .collect()
    }

    #[test]
    fn seen_cells_resolves_marks_and_near_events() {
        // 7 x 6 x 5 march cells over 7 x 6 x 5 occluder nodes, all passable but one Below node.
        let d = [7u32, 6, 5];
        let mut cls = vec![CLASS_PASS; 210];
        let below = [3u32, 1, 2];
        cls[((below[2] * d[1] + below[1]) * d[0] + below[0]) as usize] = CLASS_BELOW;
        let nodes = pack2(&cls);
        // Seen bits pass as they are; a near event along x marks the cells at x - 1 and x + 1
        // (at the border, the one inside), one along y and z the eight around it in that plane
        // but the Below node.
        let m = marks(d, &[([0, 0, 0], 1), ([5, 4, 3], 1 | 2), ([3, 2, 2], 4 | 8), ([6, 5, 4], 2)]);
        let got = cells(&seen_cells(&m, d, &nodes, d, 0), d);
        let mut want = vec![[0, 0, 0], [5, 4, 3], [4, 4, 3], [6, 4, 3], [5, 5, 4]];
        for dy in 0..3u32 {
            for dz in 0..3u32 {
                let c = [3, 1 + dy, 1 + dz];
                if c != [3, 2, 2] && c != below {
                    want.push(c);
                }
            }
        }
        want.sort_by_key(|c| (c[2], c[1], c[0]));
        assert_eq!(got, want);
    }

    #[test]
    fn seen_cells_maps_march_cells_to_coarser_nodes() {
        // March cells twice as fine as the nodes: a near event next to an Above node marks none
        // of its cells.
        let (d, od) = ([8u32, 4, 4], [4u32, 2, 2]);
        let mut cls = vec![CLASS_PASS; 16];
        cls[0] = CLASS_ABOVE;
        let nodes = pack2(&cls);
        let m = marks(d, &[([2, 1, 1], 2 | 4 | 8)]);
        let got = cells(&seen_cells(&m, d, &nodes, od, 1), d);
        // The 26 neighbours of (2, 1, 1) but the 4 in node (0, 0, 0) (x = 1, y and z in 0..2).
        assert_eq!(got.len(), 22, "{got:?}");
        assert!(got.iter().all(|c| c[0] >= 2 || c[1] >= 2 || c[2] >= 2));
        assert!(!got.contains(&[2, 1, 1]), "the event's own cell is only seen by its bit 0");
    }
}
