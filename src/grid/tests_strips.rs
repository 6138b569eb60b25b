//! Fault strips and interior faces: known answers by construction.

use super::*;

/// Fault pieces (faces split on a fault that is also a region boundary) merge into two strips
/// per side at the coarsest level of a single block, one over the cells across (interior) and
/// one over the gap beyond them: layers of thickness 1, the columns i >= 2 of a 4 x 4 x 4 grid
/// thrown down 0.4; closed and of the same volume at every level. On a seam between blocks the
/// pieces stay. An inactive cell beside the fault notches the strips (non-convex: ear
/// clipping), still closed.
#[test]
fn fault_pieces_merge_into_strips() {
    use super::faces::kind;
    let (ni, nj, nk) = (4, 4, 4);
    let c = faulted(ni, nj, nk, 0.4, 2);
    let region: Vec<i32> = (0..ni * nj * nk).map(|x| (x % ni >= 2) as i32).collect();
    let values: Vec<f64> = region.iter().map(|&r| r as f64).collect();
    let fault = |k: &KindCounts, x: usize| k[x][kind::FAULT_REGION as usize] + k[x][kind::FAULT_GAP as usize];
    let mut active = vec![true; ni * nj * nk];
    for (notch, blocks, strips) in [(false, (4, 4), Some(4)), (false, (2, 4), None), (true, (4, 4), None)] {
        if notch {
            active[(2 * nj + 1) * ni + 1] = false; // cell (k 2, j 1, i 1), beside the fault
        }
        let g =
            CornerGrid { nk, nj, ni, corners: &c, active: Some(&active), region: Some(&region), values: Some(&values) };
        let b = build(&g, blocks);
        let top = b.levels.len() - 1;
        // Level 0: the 2 x 4 x 4 faces on the fault in pieces.
        assert!(fault(&b.kinds[0], 0) > 2 * 4 * 4, "{:?}", b.kinds[0]);
        match strips {
            Some(n) => {
                assert_eq!(fault(&b.kinds[top], 0), n, "{blocks:?}: {:?}", b.kinds[top]);
                // The strips over cells are the level's interior triangles, drawn last.
                let inner = b.kinds[top][1][kind::FAULT_REGION as usize];
                assert_eq!(b.levels[top].interior_triangles, inner);
                assert!(inner > 0);
            }
            None if notch => assert!(fault(&b.kinds[top], 0) < fault(&b.kinds[0], 0) / 4, "{:?}", b.kinds[top]),
            None => assert_eq!(fault(&b.kinds[top], 0), fault(&b.kinds[0], 0), "seam: {:?}", b.kinds[top]),
        }
        for h in 0..=top {
            watertight(&b.tiles, |_| h).unwrap_or_else(|e| panic!("{blocks:?} notch {notch}, level {h}: {e}"));
            let l0 = b.levels[0].volume;
            assert!((b.levels[h].volume - l0).abs() < 1e-9 * l0, "level {h}: {} vs {l0}", b.levels[h].volume);
        }
    }
}

/// Interior faces come last in each level's index list: a 4 x 4 x 6 box of two regions (layers
/// k < 3 and k >= 3: 2 x 16 region-boundary faces), an inactive cell enclosed by region 0 and
/// one on the region boundary (cavities: 6 faces each, the second replacing a pair of boundary
/// faces) and an inactive cell on the outline (open to the outside: not interior).
#[test]
fn interior_faces_come_last() {
    let (ni, nj, nk) = (4, 4, 6);
    let c = boxed(ni, nj, nk, [1.0, 1.0, 1.0]);
    let mut active = vec![true; ni * nj * nk];
    active[(nj + 1) * ni + 1] = false; // (k 1, j 1, i 1): enclosed
    active[nj * ni + 3] = false; // (k 1, j 0, i 3): on the outline
    active[(2 * nj + 2) * ni + 2] = false; // (k 2, j 2, i 2): above region 1
    let region: Vec<i32> = (0..ni * nj * nk).map(|x| (x / (ni * nj) >= 3) as i32).collect();
    let values: Vec<f64> = region.iter().map(|&r| r as f64).collect();
    let g = CornerGrid { nk, nj, ni, corners: &c, active: Some(&active), region: Some(&region), values: Some(&values) };
    for blocks in [(4, 4), (2, 2)] {
        let b = build(&g, blocks);
        assert_eq!(b.levels[0].interior_triangles, 2 * 15 * 2 + 2 * 6 * 2, "{blocks:?}");
        for h in 0..b.levels.len() {
            watertight(&b.tiles, |_| h).unwrap();
        }
        for t in &b.tiles {
            let p = |v: u32| t.positions[v as usize];
            // Within the unit cell whose lowest corner is (x, y, z).
            let within = |tri: &[u32], q: [f64; 3]| {
                tri.iter().all(|&v| (0..3).all(|a| (q[a]..=q[a] + 1.0).contains(&(p(v)[a] as f64))))
            };
            let inner = |tri: &[u32]| {
                tri.iter().all(|&v| p(v)[2] == -3.0) || within(tri, [1.0, 1.0, -2.0]) || within(tri, [2.0, 2.0, -3.0])
            };
            let n = t.fine.len() / 3;
            let tail: usize =
                b.block_levels[(t.iy as usize) * (4 / blocks.0) + t.ix as usize][0].interior_triangles as usize;
            let tris: Vec<&[u32]> = t.fine.chunks(3).collect();
            assert!(tris[n - tail..].iter().all(|tri| inner(tri)), "{blocks:?}");
            assert!(tris[..n - tail].iter().all(|tri| !inner(tri)), "{blocks:?}");
        }
    }
}
