//! Min/max tables of a hider's blocks with heights as they are (the flat plane's queries, most of
//! the proof's): per level k, for every block (p, q), the range of the usable blocks' heights over
//! the square of 2^k × 2^k blocks from it (clipped to the grid) and whether all of them are usable.
//! A rectangle of blocks is then the union of a few squares inside it (overlapping where its sides
//! are not multiples of the square's), so a query reads a handful of entries instead of every block.
//!
//! Heights are kept in f32, rounded outwards (lows down, highs up): a range read here holds the
//! exact one, so a proof resting on it still holds.

/// The largest level: squares of 16 × 16 blocks.
const MAX_LEVEL: usize = 4;

/// How many levels the tables of a `w` × `h` grid have: up to [`MAX_LEVEL`], none of squares
/// larger than twice the grid.
fn levels_for(w: usize, h: usize) -> usize {
    (1..=MAX_LEVEL).take_while(|k| 1 << (k - 1) < w.max(h)).count() + 1
}

/// The level and square side for a `w` × `h` rectangle with `levels` levels: the largest square
/// that fits.
fn level(levels: usize, w: usize, h: usize) -> (usize, usize) {
    let k = (usize::BITS - 1 - w.min(h).max(1).leading_zeros()) as usize;
    let k = k.min(levels - 1);
    (k, 1 << k)
}

/// f64 to f32, rounded down (`up`: up): the f32 lies at or beyond `v` on that side.
fn round(v: f64, up: bool) -> f32 {
    let f = v as f32;
    match (up, f as f64 > v, (f as f64) < v) {
        (false, true, _) => f.next_down(),
        (true, _, true) => f.next_up(),
        _ => f,
    }
}

/// One level: per block, over its square, the usable blocks' lowest and highest heights
/// (+inf / -inf without any) and 1 where every block is usable (else 0).
#[derive(Clone, Debug, Default)]
struct Level {
    lo: Vec<f32>,
    hi: Vec<f32>,
    all: Vec<u8>,
}

/// The tables of one hider (module docs).
pub(super) struct FlatTable {
    w: usize,
    h: usize,
    levels: Vec<Level>,
}

/// What a query of a rectangle of blocks found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Found {
    /// The usable blocks' range (None without any).
    pub usable: Option<(f64, f64)>,
    /// Whether every block is usable.
    pub all: bool,
}

/// `out[p] = join(a[p], a[p + half], b[p], b[p + half])` along one row (`b`: the row `half`
/// below, None past the grid; entries past the row's end left out), for one of a level's arrays.
fn join_row<T: Copy>(out: &mut [T], a: &[T], b: Option<&[T]>, half: usize, f: impl Fn(T, T) -> T) {
    let w = out.len();
    out.copy_from_slice(a);
    if let Some(b) = b {
        for (o, &v) in out.iter_mut().zip(b) {
            *o = f(*o, v);
        }
    }
    if half < w {
        for (o, &v) in out.iter_mut().zip(&a[half..]) {
            *o = f(*o, v);
        }
        if let Some(b) = b {
            for (o, &v) in out.iter_mut().zip(&b[half..]) {
                *o = f(*o, v);
            }
        }
    }
}

impl FlatTable {
    /// The tables of a `w` × `h` grid of blocks, row-major: per block its (low, high) heights,
    /// None where it is not usable.
    pub fn new(w: usize, h: usize, blocks: &[Option<(f64, f64)>]) -> Self {
        debug_assert_eq!(blocks.len(), w * h);
        let first = Level {
            lo: blocks.iter().map(|b| b.map_or(f32::INFINITY, |(lo, _)| round(lo, false))).collect(),
            hi: blocks.iter().map(|b| b.map_or(f32::NEG_INFINITY, |(_, hi)| round(hi, true))).collect(),
            all: blocks.iter().map(|b| b.is_some() as u8).collect(),
        };
        let mut levels = vec![first];
        for k in 1..levels_for(w, h) {
            let half = 1 << (k - 1);
            // Each entry joins the four squares of the level below at its corners.
            let prev = &levels[k - 1];
            let mut next = Level { lo: vec![0.0; w * h], hi: vec![0.0; w * h], all: vec![0; w * h] };
            for q in 0..h {
                let row = q * w..(q + 1) * w;
                let below = (q + half < h).then(|| (q + half) * w..(q + half + 1) * w);
                let (lo_b, hi_b) = (below.clone().map(|r| &prev.lo[r]), below.clone().map(|r| &prev.hi[r]));
                join_row(&mut next.lo[row.clone()], &prev.lo[row.clone()], lo_b, half, f32::min);
                join_row(&mut next.hi[row.clone()], &prev.hi[row.clone()], hi_b, half, f32::max);
                let all_b = below.map(|r| &prev.all[r]);
                join_row(&mut next.all[row.clone()], &prev.all[row], all_b, half, |a, b| a & b);
            }
            levels.push(next);
        }
        Self { w, h, levels }
    }

    /// How many entries a query of blocks `i0..=i1` × `j0..=j1` reads in the tables of a `w` ×
    /// `h` grid (known before they are made).
    pub fn reads((w, h): (usize, usize), (i0, i1): (usize, usize), (j0, j1): (usize, usize)) -> usize {
        let (_, s) = level(levels_for(w, h), i1 - i0 + 1, j1 - j0 + 1);
        (i1 - i0 + 1).div_ceil(s) * (j1 - j0 + 1).div_ceil(s)
    }

    /// The blocks `i0..=i1` × `j0..=j1` (inside the grid).
    pub fn query(&self, (i0, i1): (usize, usize), (j0, j1): (usize, usize)) -> Found {
        debug_assert!(i0 <= i1 && i1 < self.w && j0 <= j1 && j1 < self.h);
        let (k, s) = level(self.levels.len(), i1 - i0 + 1, j1 - j0 + 1);
        let l = &self.levels[k];
        // Square starts: every s from the first, the last flush with the rectangle's far side.
        let starts = |a: usize, b: usize| (0..(b - a + 1).div_ceil(s)).map(move |n| (a + n * s).min(b + 1 - s));
        let (mut lo, mut hi, mut all) = (f32::INFINITY, f32::NEG_INFINITY, 1u8);
        for q in starts(j0, j1) {
            for p in starts(i0, i1) {
                let i = q * self.w + p;
                (lo, hi, all) = (lo.min(l.lo[i]), hi.max(l.hi[i]), all & l.all[i]);
            }
        }
        Found { usable: (lo <= hi).then_some((lo as f64, hi as f64)), all: all == 1 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (no dependency): xorshift.
    fn rng(seed: &mut u64) -> u64 {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 7;
        *seed ^= *seed << 17;
        *seed
    }

    #[test]
    fn queries_hold_the_exact_range_of_every_rectangle() {
        let mut seed = 0x9e3779b97f4a7c15;
        for (w, h) in [(1, 1), (1, 7), (13, 5), (40, 33), (70, 3)] {
            let blocks: Vec<Option<(f64, f64)>> = (0..w * h)
                .map(|_| {
                    let r = rng(&mut seed);
                    let lo = (r % 100_000) as f64 * 0.0137 - 600.0;
                    (!r.is_multiple_of(11)).then_some((lo, lo + (r >> 20) as f64 % 50.0 * 0.31))
                })
                .collect();
            let t = FlatTable::new(w, h, &blocks);
            for _ in 0..400 {
                let (a, b) = ((rng(&mut seed) as usize) % w, (rng(&mut seed) as usize) % w);
                let (c, d) = ((rng(&mut seed) as usize) % h, (rng(&mut seed) as usize) % h);
                let ((i0, i1), (j0, j1)) = ((a.min(b), a.max(b)), (c.min(d), c.max(d)));
                let blocks = &blocks;
                let cells: Vec<_> = (j0..=j1).flat_map(|j| (i0..=i1).map(move |i| blocks[j * w + i])).collect();
                let all = cells.iter().all(Option::is_some);
                let exact = cells.iter().flatten().fold(None, |r: Option<(f64, f64)>, &(lo, hi)| {
                    Some(r.map_or((lo, hi), |(a, b)| (a.min(lo), b.max(hi))))
                });
                let got = t.query((i0, i1), (j0, j1));
                assert_eq!(got.all, all);
                match (got.usable, exact) {
                    (None, None) => {}
                    (Some((lo, hi)), Some((xl, xh))) => {
                        // Holds the exact range, within f32 rounding of it.
                        assert!(lo <= xl && hi >= xh, "{lo} {hi} vs {xl} {xh}");
                        assert!(xl - lo <= 1e-4 * xl.abs().max(1.0) && hi - xh <= 1e-4 * xh.abs().max(1.0));
                    }
                    other => panic!("{other:?}"),
                }
                let s = 1usize << level(t.levels.len(), i1 - i0 + 1, j1 - j0 + 1).0;
                assert!(s <= (i1 - i0 + 1).min(j1 - j0 + 1));
                assert_eq!(t.levels.len(), levels_for(w, h));
            }
        }
    }

    #[test]
    fn f32_rounding_is_outwards() {
        for v in [0.1f64, -0.1, 1e7 + 0.3, -123456.789, 0.0, 2.5] {
            assert!((round(v, false) as f64) <= v && (round(v, true) as f64) >= v);
        }
    }
}
