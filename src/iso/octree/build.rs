//! The octree's finest stored level from the samples: in parallel over a resident volume's rows of
//! bricks, or in one streaming pass over a lazy volume's store (`super::super::store`).

use rayon::prelude::*;

use super::super::store::{slab_layers, BrickCache, OCTREE_SLAB_BYTES};
use super::{nan_max, nan_min, Level};

/// Min/max/NaN of the bricks (`s`³ cells, `level`'s cells) whose samples lie in `v`, sample layers
/// `k0 ..` of a grid of `samples` (x, y, z), for brick rows `bz0 ..` (`level`'s rows from `bz0`
/// whose last sample layer is in `v`), in parallel over the rows.
pub(super) fn brick_rows(level: &mut Level, v: &[f32], k0: usize, bz0: usize, samples: [usize; 3], s: usize) {
    let [nx, ny, nz] = samples;
    let cells = [nx - 1, ny - 1, nz - 1];
    let (bx, by) = (level.dims[0] as usize, level.dims[1] as usize);
    let slab = bx * by;
    let layers = v.len() / (nx * ny);
    // Cells b*s .. (b+1)*s of axis a (clamped), i.e. samples b*s ..= that end.
    let span = |b: usize, a: usize| (b * s, ((b + 1) * s).min(cells[a]));
    let rows = (bz0..level.dims[2] as usize).take_while(|&bz| span(bz, 2).1 < k0 + layers).count();
    let r = bz0 * slab..(bz0 + rows) * slab;
    let (min, max, nan) = (&mut level.min[r.clone()], &mut level.max[r.clone()], &mut level.nan[r]);
    min.par_chunks_mut(slab).zip(max.par_chunks_mut(slab)).zip(nan.par_chunks_mut(slab)).enumerate().for_each(
        |(row, ((mn, mx), na))| {
            let (z0, z1) = span(bz0 + row, 2);
            for byi in 0..by {
                let (y0, y1) = span(byi, 1);
                let r = byi * bx..(byi + 1) * bx;
                let (mn, mx, na) = (&mut mn[r.clone()], &mut mx[r.clone()], &mut na[r]);
                for k in z0..=z1 {
                    for j in y0..=y1 {
                        let row = &v[((k - k0) * ny + j) * nx..((k - k0) * ny + j + 1) * nx];
                        for bxi in 0..bx {
                            let (x0, x1) = span(bxi, 0);
                            let (mut lo, mut hi, mut n) = (mn[bxi], mx[bxi], na[bxi]);
                            for &x in &row[x0..=x1] {
                                lo = nan_min(lo, x);
                                hi = nan_max(hi, x);
                                n |= x.is_nan();
                            }
                            (mn[bxi], mx[bxi], na[bxi]) = (lo, hi, n);
                        }
                    }
                }
            }
        },
    );
}

/// [`brick_rows`] over a lazy volume's store: one streaming pass over slabs of whole brick rows
/// (a multiple of `s` cells, sharing their boundary layer), about 128 MiB each, not cached. An
/// infinite sample is an error kept in the store (as a read error).
pub(super) fn build_streaming(level: &mut Level, store: &BrickCache, samples: [usize; 3], s: usize) {
    let layers = (slab_layers(samples[0] * samples[1], OCTREE_SLAB_BYTES).saturating_sub(1) / s).max(1) * s + 1;
    let mut inf = None;
    store.for_each_slab(layers, 1, |k0, slab| {
        if inf.is_none() {
            if let Some(p) = slab.par_iter().position_first(|v| v.is_infinite()) {
                let layer = samples[0] * samples[1];
                inf = Some([p % samples[0], p % layer / samples[0], k0 + p / layer]);
            }
        }
        brick_rows(level, slab, k0, k0 / s, samples, s);
    });
    if let Some([i, j, k]) = inf {
        store.fail(crate::error::input_err(
            "values",
            format!("the stored sample [{k}, {j}, {i}] (z up, zyx) is infinite; use NaN for no data"),
        ));
    }
}
