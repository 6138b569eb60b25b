//! Clearance: how far, vertically, a height-field tile's fine surface stays from every other
//! object, which tells whether a coarser level of it needs the fine surface's depth.
//!
//! A height-field tile drawn at a coarser level lies within that level's vertical error `e` of its
//! fine surface (`levels::lattice_levels`). Where another object's surface comes within `e` of it
//! (a grid's top built from the horizon, a fault or a well through it), the two cross along lines
//! that the level moves by far more than `e` on screen, so such tiles write the fine surface's
//! depth (draw.wgsl `fine_depth`, which costs the early depth test of every fragment). Where no
//! other object comes within `e`, the level shows and hides what the fine tile does up to the
//! level's own error, and it is drawn as any level is.
//!
//! Contract of [`clearances`]: given every tile's parts (boxes, placed in one common frame, whose
//! union holds the tile's triangles; a height-field tile's are its height blocks'), for each
//! height-field tile the smallest vertical gap between one of its parts and a part of another
//! object that overlaps it in (x, y) (0 where they overlap in z too), +inf where none overlaps; a
//! lower bound of the vertical distance from the tile's fine surface to any other object's
//! triangle over the same (x, y). Other tiles get 0 (never asked).

/// One tile's parts as [`clearances`] reads them.
#[derive(Clone, Debug, Default)]
pub struct TileParts {
    /// The tile's object: parts of the same object never count against each other.
    pub object: u32,
    /// Whether the tile is a height-field tile (its clearance is measured).
    pub field: bool,
    /// Boxes (lo, hi), placed, whose union holds the tile's triangles.
    pub boxes: Vec<([f64; 3], [f64; 3])>,
}

/// The clearance of every tile (see the module's contract), in parallel over the tiles.
pub fn clearances(tiles: &[TileParts]) -> Vec<f32> {
    use rayon::prelude::*;
    let index = Index::new(tiles);
    tiles
        .par_iter()
        .map(|t| {
            if !t.field {
                return 0.0;
            }
            let mut gap = f64::INFINITY;
            for (lo, hi) in &t.boxes {
                index.for_each_near(*lo, *hi, |k, (plo, phi)| {
                    if tiles[k].object != t.object && overlap_xy((*lo, *hi), (plo, phi)) {
                        gap = gap.min((plo[2] - hi[2]).max(lo[2] - phi[2]).max(0.0));
                    }
                });
                if gap == 0.0 {
                    break;
                }
            }
            // Rounded down: a bound from below.
            let g = gap as f32;
            if g as f64 > gap {
                g.next_down()
            } else {
                g
            }
        })
        .collect()
}

fn overlap_xy((alo, ahi): ([f64; 3], [f64; 3]), (blo, bhi): ([f64; 3], [f64; 3])) -> bool {
    alo[0] <= bhi[0] && blo[0] <= ahi[0] && alo[1] <= bhi[1] && blo[1] <= ahi[1]
}

/// The parts of every tile in a uniform (x, y) grid of cells about the size of a median part, each
/// part listed in every cell its (x, y) box touches.
struct Index<'a> {
    lo: [f64; 2],
    cell: f64,
    dims: [usize; 2],
    /// Per cell, (tile, part) of the parts touching it.
    cells: Vec<Vec<(u32, u32)>>,
    tiles: &'a [TileParts],
}

impl<'a> Index<'a> {
    fn new(tiles: &'a [TileParts]) -> Self {
        let all = || tiles.iter().flat_map(|t| t.boxes.iter());
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let mut sizes = Vec::new();
        for (l, h) in all() {
            for a in 0..2 {
                lo[a] = lo[a].min(l[a]);
                hi[a] = hi[a].max(h[a]);
            }
            sizes.push((h[0] - l[0]).max(h[1] - l[1]));
        }
        if sizes.is_empty() {
            return Index { lo: [0.0; 2], cell: 1.0, dims: [1, 1], cells: vec![Vec::new()], tiles };
        }
        sizes.sort_unstable_by(f64::total_cmp);
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        // A median part a cell, at most 1024 cells a side (and a positive size for a flat scene).
        let cell = sizes[sizes.len() / 2].max(extent / 1024.0).max(1e-9 * (1.0 + extent));
        let dims = [0, 1].map(|a| (((hi[a] - lo[a]) / cell) as usize + 1).min(1024));
        let mut index = Index { lo, cell, dims, cells: vec![Vec::new(); dims[0] * dims[1]], tiles };
        for (k, t) in tiles.iter().enumerate() {
            for (p, (l, h)) in t.boxes.iter().enumerate() {
                let ([i0, j0], [i1, j1]) = (index.at(*l), index.at(*h));
                for j in j0..=j1 {
                    for i in i0..=i1 {
                        index.cells[j * dims[0] + i].push((k as u32, p as u32));
                    }
                }
            }
        }
        index
    }

    /// The cell holding (x, y), clamped to the grid.
    fn at(&self, p: [f64; 3]) -> [usize; 2] {
        [0, 1].map(|a| (((p[a] - self.lo[a]) / self.cell).max(0.0) as usize).min(self.dims[a] - 1))
    }

    /// Calls `f(tile, part)` for every part in the cells that (lo, hi)'s (x, y) box touches (a
    /// part in several of them more than once).
    fn for_each_near(&self, lo: [f64; 3], hi: [f64; 3], mut f: impl FnMut(usize, ([f64; 3], [f64; 3]))) {
        let ([i0, j0], [i1, j1]) = (self.at(lo), self.at(hi));
        for j in j0..=j1 {
            for i in i0..=i1 {
                for &(k, p) in &self.cells[j * self.dims[0] + i] {
                    f(k as usize, self.tiles[k as usize].boxes[p as usize]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn part(object: u32, field: bool, boxes: &[([f64; 3], [f64; 3])]) -> TileParts {
        TileParts { object, field, boxes: boxes.to_vec() }
    }

    #[test]
    fn the_gap_to_the_nearest_other_object_over_the_same_ground() {
        let tiles = [
            // A horizon tile at z 0..2 over (0..10, 0..10), two blocks.
            part(0, true, &[([0.0, 0.0, 0.0], [5.0, 10.0, 1.0]), ([5.0, 0.0, 1.0], [10.0, 10.0, 2.0])]),
            // Its neighbour in the same object, touching it and higher: never counts.
            part(0, true, &[([10.0, 0.0, 1.5], [20.0, 10.0, 3.0])]),
            // A horizon 30 above the first block only, and a box of another object under the
            // second block, 4 below it.
            part(1, true, &[([0.0, 0.0, 31.0], [4.0, 10.0, 33.0])]),
            part(2, false, &[([6.0, 2.0, -5.0], [8.0, 4.0, -3.0])]),
            // Far away in (x, y): no overlap.
            part(3, false, &[([100.0, 100.0, 0.0], [110.0, 110.0, 5.0])]),
        ];
        let c = clearances(&tiles);
        assert_eq!(c[0], 4.0, "the box under the second block, 4 below it");
        assert_eq!(c[1], f32::INFINITY, "nothing of another object under the neighbour");
        assert_eq!(c[2], 30.0, "30 above the first block");
        assert_eq!(c[3], 0.0, "not a height field");
        // A well through the first tile: clearance 0.
        let mut with_well = tiles.to_vec();
        with_well.push(part(4, false, &[([2.0, 2.0, -50.0], [3.0, 3.0, 50.0])]));
        assert_eq!(clearances(&with_well)[0], 0.0);
    }

    #[test]
    fn the_grid_index_finds_what_brute_force_finds() {
        // Random boxes of random objects: every clearance equals the pairwise minimum.
        let mut rng = crate::TestRng(99);
        let mut rnd = || rng.f();
        let tiles: Vec<TileParts> = (0..200)
            .map(|k| {
                let boxes = (0..1 + k % 4)
                    .map(|_| {
                        let (x, y, z) = (1000.0 * rnd(), 1000.0 * rnd(), 200.0 * rnd());
                        let (w, d, h) = (80.0 * rnd() + 1.0, 80.0 * rnd() + 1.0, 30.0 * rnd());
                        ([x, y, z], [x + w, y + d, z + h])
                    })
                    .collect();
                TileParts { object: (k % 7) as u32, field: k % 3 != 0, boxes }
            })
            .collect();
        let got = clearances(&tiles);
        for (k, t) in tiles.iter().enumerate() {
            if !t.field {
                continue;
            }
            let mut want = f64::INFINITY;
            for u in tiles.iter().filter(|u| u.object != t.object) {
                for a in &t.boxes {
                    for b in &u.boxes {
                        if overlap_xy(*a, *b) {
                            want = want.min((b.0[2] - a.1[2]).max(a.0[2] - b.1[2]).max(0.0));
                        }
                    }
                }
            }
            let g = got[k] as f64;
            assert!(g == want || (g < want && want - g <= 1e-4 * want.max(1.0)), "{k}: {g} {want}");
        }
    }
}
