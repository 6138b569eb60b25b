//! A scene as bytes and back (for pickling, copies across processes): a small versioned
//! little-endian layout of the scene's origin, its objects and their tiles, exactly as stored
//! (f32 origin-relative positions, both index levels), so a scene read back renders the same image.
//!
//! Layout, version 11 (every integer and float little-endian; `str` = u32 byte length + UTF-8;
//! arrays = u64 element count + elements):
//!
//! ```text
//! magic b"GCSCENE\0", version u32
//! has_origin u8, origin f64 x 3, next_id u32, n_objects u32
//! per object: id u32, name str, kind u8 (0 = height field, 1 = mesh, 2 = grid, version 4),
//!   height field: nx u64, ny u64, x0 f64, y0 f64, dx f64, dy f64 (< 0: yflip), rotation f64
//!                 (degrees; absent in version 1, read as 0), tx u64, ty u64 | mesh: label str |
//!   grid: nk, nj, ni, bi, bj u64, block cell sizes [f32 x 2], levels, then n_blocks u32 and
//!         each block's levels (levels = n u32, per level cells, faces, triangles, vertices u64,
//!         volume f64, interior_triangles u64 (version 5; read as 0 before))
//!   color f32 x 3, visible u8, offset f64 x 3, origin f64 x 3 (the object's own; absent before
//!   version 3, read as the scene's),
//!   color_by u8 (0 = flat, 1 = z, 2 = values; version 4), if not flat: cmap str, lut [f32 x 3]
//!   (256 rows), clim f64 x 2, nan_color f32 x 3; opacity f32 (version 4); priority u8 (version 7:
//!   0..=15, 255 = by kind; absent before, by kind); n_tiles u32
//!   per tile: ix u32, iy u32, bbox_min f32 x 3, bbox_max f32 x 3,
//!             positions [f32 x 3], values [f32] (version 4: empty or one per position),
//!             normals [u32] (version 5: packed smooth normals, empty or one per position),
//!             grid_uv [u32] (version 6: packed grid coordinates, empty or one per position),
//!             ring_z [f32] (version 9: a tube's ring heights, empty or one per position),
//!             stations [f32] (version 11: a log-coloured tube's stations, empty or one per
//!             position),
//!             fine [u32], coarse [u32], proxy_error f32,
//!             levels: n u32, then per level error f32, shading_error f32 (version 6; before,
//!             measured again on reading: `lod::shading`, 0 for height fields and grids),
//!             error_z f32 (version 8; before, the error), indices [u32], then (version 10;
//!             none before) grouped_error f32, n_grouped u32 (version 12: 0 or 15), that many
//!             indices [u32]: version 12, the variants by side mask (`lod::groups`); versions 10
//!             and 11, at most 6 variants by group depth, which reading drops (their levels then
//!             draw with full borders, the group error their error)
//! ```
//!
//! Reading checks what later stages rely on (index bounds, finite positions, whole triangles) and
//! reports a damaged or foreign buffer as an InputError naming `data`.

use super::color::{resolve_clim, LUT_SIZE};
use super::{ColorBy, ColorSource, HeightfieldInfo, Object, ObjectKind, Scene, NEXT_SCENE_UID};
use crate::error::{input_err, Error, Result};
use crate::lod::slab::TileSlabs;
use crate::lod::{PerVertex, TileMesh};
use glam::DVec3;
use std::sync::atomic::Ordering;

#[path = "serial_check.rs"]
mod check;

const MAGIC: &[u8; 8] = b"GCSCENE\0";
const VERSION: u32 = 12;

/// The fewest bytes a tile takes in any version (version 1: ix, iy, box, positions, fine and
/// coarse empty, proxy error, no levels).
const MIN_TILE_BYTES: usize = 8 + 24 + 8 + 8 + 8 + 4 + 4;

/// The fewest bytes a tile takes in `version`: [`MIN_TILE_BYTES`] and the counts of its empty
/// values (version 4), normals (5), grid coordinates (6), ring heights (9) and stations (11): 104
/// bytes from version 11.
fn min_tile_bytes(version: u32) -> usize {
    MIN_TILE_BYTES + 8 * [4, 5, 6, 9, 11].iter().filter(|&&v| version >= v).count()
}

/// The fewest bytes an object takes in `version`: a mesh (the smallest kind: its label's length)
/// with no name nor tiles: id, name, kind, label, colour, visible, offset, tile count (54 bytes),
/// its origin (version 3), colouring and opacity (4), priority (7): 84 bytes from version 7 on.
fn min_object_bytes(version: u32) -> usize {
    let later = [(3, 24), (4, 5), (7, 1)];
    54 + later.iter().filter(|&&(v, _)| version >= v).map(|&(_, b)| b).sum::<usize>()
}

/// What a declared object record claims of the buffer in `version` ([`Reader::records`]): its
/// fewest bytes, and at least half the struct it is read into, so that the objects, reserved
/// whole, take at most twice their bytes in every version (version 1's empty object takes 54
/// bytes, an [`Object`] 160). Every object a writer makes takes more than either.
fn object_claim(version: u32) -> usize {
    min_object_bytes(version).max(std::mem::size_of::<Object>().div_ceil(2))
}

/// A declared tile record's claim in `version`, as [`object_claim`]'s: its fewest bytes, and at
/// least half a [`TileMesh`].
fn tile_claim(version: u32) -> usize {
    min_tile_bytes(version).max(std::mem::size_of::<TileMesh>().div_ceil(2))
}

/// Little-endian writer.
#[derive(Default)]
pub(crate) struct Writer(pub(crate) Vec<u8>);

impl Writer {
    pub(crate) fn bytes(&mut self, b: &[u8]) {
        self.0.extend_from_slice(b);
    }
    pub(crate) fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    pub(crate) fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }
    pub(crate) fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
    pub(crate) fn f32(&mut self, v: f32) {
        self.bytes(&v.to_le_bytes());
    }
    pub(crate) fn f64(&mut self, v: f64) {
        self.bytes(&v.to_le_bytes());
    }
    pub(crate) fn str(&mut self, s: &str) {
        self.u32(s.len() as u32);
        self.bytes(s.as_bytes());
    }
    pub(crate) fn f32s(&mut self, v: &[f32]) {
        self.u64(v.len() as u64);
        self.0.reserve(v.len() * 4);
        for x in v {
            self.f32(*x);
        }
    }
    pub(crate) fn u32s(&mut self, v: &[u32]) {
        self.u64(v.len() as u64);
        self.0.reserve(v.len() * 4);
        for x in v {
            self.u32(*x);
        }
    }
}

/// Little-endian reader over a buffer; every error names `arg`.
///
/// Records declared by a count ([`Self::records`]) claim the fewest bytes each can take until
/// each is read: arrays, strings and further counts may only take bytes no record claims. Every
/// byte of the buffer then backs at most one thing held in memory, so the records' vectors can
/// be reserved whole (no vector grows while reading, which holds its old and new blocks at
/// once), and loading stays within about twice the buffer's size (issue 39,
/// tests/alloc_bound.rs) however the counts are damaged.
pub(crate) struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
    arg: &'static str,
    /// Bytes claimed by records declared and not started yet ([`Self::records`]).
    claimed: usize,
}

impl<'a> Reader<'a> {
    pub(crate) fn new(buf: &'a [u8], arg: &'static str) -> Self {
        Self { buf, pos: 0, arg, claimed: 0 }
    }
    pub(crate) fn err(&self, what: impl std::fmt::Display) -> Error {
        input_err(self.arg, format!("{} at byte {}: {what}", self.arg, self.pos))
    }
    pub(crate) fn take(&mut self, n: usize) -> Result<&'a [u8]> {
        if self.buf.len() - self.pos < n {
            return Err(self.err(format!("truncated ({} bytes, {n} more needed)", self.buf.len())));
        }
        let s = &self.buf[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    fn arr<const N: usize>(&mut self) -> Result<[u8; N]> {
        Ok(self.take(N)?.try_into().expect("length checked"))
    }
    pub(crate) fn u8(&mut self) -> Result<u8> {
        Ok(self.take(1)?[0])
    }
    pub(crate) fn u32(&mut self) -> Result<u32> {
        Ok(u32::from_le_bytes(self.arr()?))
    }
    pub(crate) fn u64(&mut self) -> Result<u64> {
        Ok(u64::from_le_bytes(self.arr()?))
    }
    pub(crate) fn usize(&mut self) -> Result<usize> {
        let v = self.u64()?;
        usize::try_from(v).map_err(|_| self.err(format!("count {v} is too large")))
    }
    pub(crate) fn f32(&mut self) -> Result<f32> {
        Ok(f32::from_le_bytes(self.arr()?))
    }
    pub(crate) fn f64(&mut self) -> Result<f64> {
        Ok(f64::from_le_bytes(self.arr()?))
    }
    pub(crate) fn str(&mut self) -> Result<String> {
        let n = self.u32()? as usize;
        if n > self.unclaimed() {
            return Err(self.err(format!("a name of {n} bytes does not fit the buffer")));
        }
        let b = self.take(n)?;
        String::from_utf8(b.to_vec()).map_err(|_| self.err("a name is not UTF-8"))
    }
    /// Bytes not read yet.
    pub(crate) fn remaining(&self) -> usize {
        self.buf.len() - self.pos
    }
    /// Bytes not read yet that no declared record claims: what an array, a string or a count of
    /// records may take.
    pub(crate) fn unclaimed(&self) -> usize {
        self.remaining().saturating_sub(self.claimed)
    }
    /// Declares `n` records (`what`) of at least `min` bytes each to follow: refused when the
    /// unclaimed bytes cannot hold them, else claimed until each starts ([`Self::record`]).
    pub(crate) fn records(&mut self, n: usize, min: usize, what: &str) -> Result<()> {
        let left = self.unclaimed();
        match n.checked_mul(min) {
            Some(b) if b <= left => {
                self.claimed += b;
                Ok(())
            }
            _ => Err(self.err(format!("truncated ({n} {what} of at least {min} bytes each; {left} bytes left)"))),
        }
    }
    /// Starts reading one of the records [`Self::records`] declared with this `min`: its bytes
    /// are no longer claimed (it reads them now).
    pub(crate) fn record(&mut self, min: usize) {
        self.claimed = self.claimed.saturating_sub(min);
    }
    /// A count of `elem`-byte elements that the unclaimed rest of the buffer can hold.
    fn count(&mut self, elem: usize) -> Result<usize> {
        let n = self.usize()?;
        if n.checked_mul(elem).is_none_or(|b| b > self.unclaimed()) {
            return Err(self.err(format!("an array of {n} elements does not fit the buffer")));
        }
        Ok(n)
    }
    pub(crate) fn f32s(&mut self) -> Result<Vec<f32>> {
        let n = self.count(4)?;
        Ok(self.take(4 * n)?.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect())
    }
    pub(crate) fn u32s(&mut self) -> Result<Vec<u32>> {
        let n = self.count(4)?;
        Ok(self.take(4 * n)?.chunks_exact(4).map(|c| u32::from_le_bytes(c.try_into().unwrap())).collect())
    }
    pub(crate) fn f64x3(&mut self) -> Result<[f64; 3]> {
        Ok([self.f64()?, self.f64()?, self.f64()?])
    }
    pub(crate) fn f32x3(&mut self) -> Result<[f32; 3]> {
        Ok([self.f32()?, self.f32()?, self.f32()?])
    }
    /// The magic and a version this build reads.
    pub(crate) fn header(&mut self, magic: &[u8; 8], what: &str, newest: u32) -> Result<u32> {
        if self.take(8).ok() != Some(&magic[..]) {
            self.pos = 0;
            return Err(self.err(format!("not a geocull {what} (wrong magic bytes)")));
        }
        let v = self.u32()?;
        if v == 0 || v > newest {
            return Err(self.err(format!("{what} format version {v}; this geocull reads versions 1..={newest}")));
        }
        Ok(v)
    }
    pub(crate) fn finish(&self) -> Result<()> {
        if self.pos != self.buf.len() {
            return Err(self.err(format!("{} unexpected trailing bytes", self.buf.len() - self.pos)));
        }
        Ok(())
    }
}

impl Scene {
    /// The scene as bytes (see the module docs for the layout); [`Scene::from_bytes`] reads them.
    pub fn to_bytes(&self) -> Vec<u8> {
        self.write(VERSION)
    }

    fn write(&self, version: u32) -> Vec<u8> {
        let mut w = Writer::default();
        w.bytes(MAGIC);
        w.u32(version);
        w.u8(self.origin.is_some() as u8);
        for a in self.origin().to_array() {
            w.f64(a);
        }
        w.u32(self.next_id);
        w.u32(self.objects.len() as u32);
        for o in &self.objects {
            w.u32(o.id);
            w.str(&o.name);
            match &o.kind {
                ObjectKind::Heightfield(hf) => {
                    w.u8(0);
                    for v in [hf.nx, hf.ny] {
                        w.u64(v as u64);
                    }
                    for v in [hf.x0, hf.y0, hf.dx, hf.dy, hf.rotation] {
                        w.f64(v);
                    }
                    for v in [hf.tiles.0, hf.tiles.1] {
                        w.u64(v as u64);
                    }
                }
                ObjectKind::Mesh { kind } => {
                    w.u8(1);
                    w.str(kind);
                }
                ObjectKind::Grid(g) => {
                    w.u8(2);
                    for v in [g.dims.0, g.dims.1, g.dims.2, g.blocks.0, g.blocks.1] {
                        w.u64(v as u64);
                    }
                    w.f32s(&g.cell_size.iter().flat_map(|c| [c.0 as f32, c.1 as f32]).collect::<Vec<_>>());
                    let put = |w: &mut Writer, ls: &[crate::grid::LevelStats]| {
                        w.u32(ls.len() as u32);
                        for l in ls {
                            for v in [l.cells, l.faces, l.triangles, l.vertices] {
                                w.u64(v);
                            }
                            w.f64(l.volume);
                            w.u64(l.interior_triangles);
                        }
                    };
                    put(&mut w, &g.levels);
                    w.u32(g.block_levels.len() as u32);
                    for b in &g.block_levels {
                        put(&mut w, b);
                    }
                }
            }
            for c in o.color {
                w.f32(c);
            }
            w.u8(o.visible as u8);
            for a in o.offset.to_array() {
                w.f64(a);
            }
            for a in o.origin.to_array() {
                w.f64(a);
            }
            match &o.color_by {
                None => w.u8(0),
                Some(c) => {
                    w.u8(if c.source == ColorSource::Z { 1 } else { 2 });
                    w.str(&c.cmap);
                    w.f32s(bytemuck::cast_slice(&c.lut));
                    w.f64(c.clim[0]);
                    w.f64(c.clim[1]);
                    for v in c.nan_color {
                        w.f32(v);
                    }
                }
            }
            w.f32(o.opacity);
            w.u8(o.priority.unwrap_or(u8::MAX));
            w.u32(o.tiles.len() as u32);
            for t in &o.tiles {
                w.u32(t.ix);
                w.u32(t.iy);
                for v in t.bbox_min.iter().chain(&t.bbox_max) {
                    w.f32(*v);
                }
                w.f32s(bytemuck::cast_slice(&t.positions));
                w.f32s(&t.values);
                w.u32s(&t.normals);
                w.u32s(&t.grid_uv);
                if version >= 9 {
                    w.f32s(&t.ring_z);
                }
                if version >= 11 {
                    w.f32s(&t.stations);
                }
                w.u32s(&t.fine);
                w.u32s(&t.coarse);
                w.f32(t.proxy_error);
                w.u32(t.levels.len() as u32);
                for l in &t.levels {
                    w.f32(l.error);
                    w.f32(l.shading_error);
                    w.f32(l.error_z);
                    w.u32s(&l.indices);
                    if version >= 10 {
                        w.f32(l.grouped_error);
                        let n = if version >= 12 { l.grouped.len() } else { l.grouped.len().min(6) };
                        w.u32(n as u32);
                        for g in &l.grouped[..n] {
                            w.u32s(g);
                        }
                    }
                }
            }
        }
        w.0
    }

    /// A scene read from [`Scene::to_bytes`]'s bytes: the same objects, ids and tiles (so it
    /// renders the same image), under a new identity (renderers upload it afresh). Each object is
    /// checked once read (`check`): damaged or foreign bytes are an InputError naming `data`.
    pub fn from_bytes(data: &[u8]) -> Result<Scene> {
        let mut r = Reader::new(data, "data");
        let version = r.header(MAGIC, "scene", VERSION)?;
        let has_origin = r.u8()? != 0;
        let origin = DVec3::from_array(r.f64x3()?);
        check::point(origin, "origin").map_err(|e| r.err(e))?;
        let next_id = r.u32()?;
        let n = r.u32()? as usize;
        let min_object = object_claim(version);
        r.records(n, min_object, "objects")?;
        let mut objects: Vec<Object> = Vec::with_capacity(n);
        for _ in 0..n {
            r.record(min_object);
            let start = r.pos;
            let id = r.u32()?;
            // Ids grow with every object added and removing one keeps the order: ascending.
            if id >= next_id || objects.last().is_some_and(|o| o.id >= id) {
                return Err(r.err(format!("object id {id} is repeated, out of order or not below next id {next_id}")));
            }
            let name = r.str()?;
            let kind = read_kind(&mut r, version, id)?;
            let color = r.f32x3()?;
            let visible = r.u8()? != 0;
            let offset = DVec3::from_array(r.f64x3()?);
            // Version 3: each object's own origin; before, every object used the scene's.
            let object_origin = if version >= 3 { DVec3::from_array(r.f64x3()?) } else { origin };
            let placed = check::point(object_origin, "origin").and_then(|_| check::point(offset, "offset"));
            placed.and_then(|_| check::rgb(color, "color")).map_err(|e| r.err(format!("object {id}: {e}")))?;
            let color_by = read_color_by(&mut r, version, id)?;
            let opacity = if version >= 4 { r.f32()? } else { 1.0 };
            if !(opacity > 0.0 && opacity <= 1.0) {
                return Err(r.err(format!("object {id}: its opacity is not in (0, 1]")));
            }
            let priority = if version >= 7 { r.u8()? } else { u8::MAX };
            if priority > super::MAX_PRIORITY && priority != u8::MAX {
                return Err(r.err(format!("object {id}: its priority {priority} is not in 0..=15")));
            }
            let nt = r.u32()? as usize;
            let min_tile = tile_claim(version);
            r.records(nt, min_tile, "tiles")?;
            let mut tiles = Vec::with_capacity(nt);
            for t in 0..nt {
                r.record(min_tile);
                let tile = read_tile(&mut r, version, id, &kind)?;
                check::tile(&tile, object_origin).map_err(|e| r.err(format!("object {id}: tile {t}: {e}")))?;
                tiles.push(tile);
            }
            if color_by.as_ref().is_some_and(|c| c.source == ColorSource::Values)
                && tiles.iter().all(|t: &TileMesh| t.values.is_empty())
            {
                return Err(r.err(format!("object {id}: coloured by values but has none")));
            }
            check::object(&kind, &tiles, object_origin, r.pos - start)
                .map_err(|e| r.err(format!("object {id}: {e}")))?;
            crate::lod::share_indices(&mut tiles);
            objects.push(Object {
                id,
                name,
                kind,
                color,
                color_by,
                opacity,
                priority: (priority != u8::MAX).then_some(priority),
                visible,
                offset,
                origin: object_origin,
                tiles,
                geometry_stamp: super::new_geometry_stamp(),
                // Not stored: a scene read from bytes culls its isosurfaces as plain meshes.
                occluders: None,
            });
        }
        r.finish()?;
        // Slabs are not stored: a height field's are rebuilt from its tiles' vertices, as they
        // were built, when a renderer first needs them (`Object::slabs`), not here.
        Ok(Scene {
            uid: NEXT_SCENE_UID.fetch_add(1, Ordering::Relaxed),
            geometry_version: 0,
            origin: has_origin.then_some(origin),
            objects,
            next_id,
            last_add: None,
            replaced: Vec::new(),
        })
    }
}

/// An object's kind and what it keeps besides its tiles (height field frame, mesh label, grid
/// tables), as read; checked against the tiles later (`check::object`).
fn read_kind(r: &mut Reader, version: u32, id: u32) -> Result<ObjectKind> {
    Ok(match r.u8()? {
        0 => {
            let (nx, ny) = (r.usize()?, r.usize()?);
            let (x0, y0, dx, dy) = (r.f64()?, r.f64()?, r.f64()?, r.f64()?);
            let rotation = if version >= 2 { r.f64()? } else { 0.0 };
            let tiles = (r.usize()?, r.usize()?);
            let slabs = TileSlabs::default();
            ObjectKind::Heightfield(Box::new(HeightfieldInfo { nx, ny, x0, y0, dx, dy, rotation, tiles, slabs }))
        }
        1 => ObjectKind::Mesh { kind: r.str()? },
        2 if version >= 4 => {
            let d = [r.usize()?, r.usize()?, r.usize()?, r.usize()?, r.usize()?];
            let flat = r.f32s()?;
            // One pair per block, and a tile per block to follow (`check::grid`): no more pairs
            // than tiles fit the rest (they are stored as f64, twice the bytes read).
            if flat.len() % 2 != 0 || flat.len() / 2 > r.unclaimed() / tile_claim(version) {
                return Err(r.err(format!("object {id}: its block cell sizes are not pairs, one per tile")));
            }
            let cell_size: Vec<(f64, f64)> = flat.chunks_exact(2).map(|c| (c[0] as f64, c[1] as f64)).collect();
            drop(flat);
            let get = |r: &mut Reader| -> Result<Vec<crate::grid::LevelStats>> {
                let n = r.u32()? as usize;
                // Each level takes 40 bytes (48 from version 5): a count the rest cannot hold is
                // refused before anything is reserved for it.
                let each = if version >= 5 { 48 } else { 40 };
                if n.checked_mul(each).is_none_or(|b| b > r.unclaimed()) {
                    return Err(r.err(format!("object {id}: a table of {n} grid levels does not fit the buffer")));
                }
                let mut v = Vec::with_capacity(n);
                for _ in 0..n {
                    let (cells, faces, triangles, vertices) = (r.u64()?, r.u64()?, r.u64()?, r.u64()?);
                    let volume = r.f64()?;
                    // Version 4 did not order interior faces last: none is left out.
                    let interior_triangles = if version >= 5 { r.u64()?.min(triangles) } else { 0 };
                    v.push(crate::grid::LevelStats { cells, faces, triangles, vertices, volume, interior_triangles });
                }
                Ok(v)
            };
            let levels = get(r)?;
            let nb = r.u32()? as usize;
            // A table per block (`check::grid`), as many as the cell sizes above, which the rest
            // holds a tile each for: reserved whole.
            if nb != cell_size.len() {
                return Err(r.err(format!("object {id}: {nb} grid block tables for {} blocks", cell_size.len())));
            }
            let mut block_levels = Vec::with_capacity(nb);
            for _ in 0..nb {
                block_levels.push(get(r)?);
            }
            ObjectKind::Grid(Box::new(crate::scene::grid::GridInfo {
                dims: (d[0], d[1], d[2]),
                blocks: (d[3], d[4]),
                cell_size,
                levels,
                block_levels,
            }))
        }
        k => return Err(r.err(format!("unknown object kind {k}"))),
    })
}

/// An object's colouring by data (None: flat), its colour map and range checked as when set.
fn read_color_by(r: &mut Reader, version: u32, id: u32) -> Result<Option<Box<ColorBy>>> {
    Ok(if version >= 4 {
        let source = match r.u8()? {
            0 => None,
            1 => Some(ColorSource::Z),
            2 => Some(ColorSource::Values),
            k => return Err(r.err(format!("object {id}: unknown colouring {k}"))),
        };
        match source {
            None => None,
            Some(source) => {
                let cmap = r.str()?;
                let flat = r.f32s()?;
                if flat.len() != 3 * LUT_SIZE || flat.iter().any(|v| !(0.0..=1.0).contains(v)) {
                    return Err(r.err(format!("object {id}: its colour map is not {LUT_SIZE} RGB rows in [0, 1]")));
                }
                let lut = flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
                let (lo, hi) = (r.f64()?, r.f64()?);
                let clim = resolve_clim(Some([lo, hi]), std::iter::empty())
                    .map_err(|_| r.err(format!("object {id}: its colour range is not finite lo < hi")))?;
                let nan_color = r.f32x3()?;
                check::rgb(nan_color, "nan_color").map_err(|e| r.err(format!("object {id}: {e}")))?;
                Some(Box::new(ColorBy { source, cmap, lut, clim, nan_color }))
            }
        }
    } else {
        None
    })
}

/// One tile of object `id` (of `kind`): per-vertex arrays one per position, indices within the
/// positions, at most `MAX_LEVELS` levels.
fn read_tile(r: &mut Reader, version: u32, id: u32, kind: &ObjectKind) -> Result<TileMesh> {
    let (ix, iy) = (r.u32()?, r.u32()?);
    let (bbox_min, bbox_max) = (r.f32x3()?, r.f32x3()?);
    let flat = r.f32s()?;
    if flat.len() % 3 != 0 || flat.iter().any(|v| !v.is_finite()) {
        return Err(r.err(format!("object {id}: tile positions are not finite xyz triples")));
    }
    let positions: Vec<[f32; 3]> = flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    // Per-vertex attributes: none, or one per position.
    let per_vertex = |what: &str, len: usize| {
        (len != 0 && len != positions.len())
            .then(|| format!("object {id}: a tile has {len} {what} for {} vertices", positions.len()))
    };
    let values: PerVertex<f32> = if version >= 4 { r.f32s()?.into() } else { PerVertex::new() };
    if let Some(msg) = per_vertex("values", values.len()) {
        return Err(r.err(msg));
    }
    let normals: PerVertex<u32> = if version >= 5 { r.u32s()?.into() } else { PerVertex::new() };
    if let Some(msg) = per_vertex("normals", normals.len()) {
        return Err(r.err(msg));
    }
    let grid_uv: PerVertex<u32> = if version >= 6 { r.u32s()?.into() } else { PerVertex::new() };
    if let Some(msg) = per_vertex("grid coordinates", grid_uv.len()) {
        return Err(r.err(msg));
    }
    let ring_z: PerVertex<f32> = if version >= 9 { r.f32s()?.into() } else { PerVertex::new() };
    if let Some(msg) = per_vertex("ring heights", ring_z.len()) {
        return Err(r.err(msg));
    }
    let stations: PerVertex<f32> = if version >= 11 { r.f32s()?.into() } else { PerVertex::new() };
    if let Some(msg) = per_vertex("stations", stations.len()) {
        return Err(r.err(msg));
    }
    let (fine, coarse) = (indices(r.u32s()?), indices(r.u32s()?));
    let proxy_error = r.f32()?;
    let nl = r.u32()? as usize;
    if nl > crate::lod::levels::MAX_LEVELS {
        return Err(
            r.err(format!("object {id}: a tile has {nl} LOD levels; at most {}", crate::lod::levels::MAX_LEVELS))
        );
    }
    let mut levels = Vec::with_capacity(nl.min(64));
    for _ in 0..nl {
        let error = r.f32()?;
        let shading_error = if version >= 6 { r.f32()? } else { f32::NAN };
        let error_z = if version >= 8 { r.f32()? } else { error };
        let level_indices = indices(r.u32s()?);
        let (grouped_error, mut grouped) = (if version >= 10 { r.f32()? } else { error }, Vec::new());
        if version >= 10 {
            let ng = r.u32()? as usize;
            let (variants, now) = (crate::lod::groups::VARIANTS, version >= 12);
            if if now { ng != 0 && ng != variants } else { ng > 6 } {
                let want = if now { format!("0 or {variants}") } else { "at most 6".into() };
                return Err(r.err(format!("object {id}: a tile's level has {ng} group variants; {want}")));
            }
            for _ in 0..ng {
                grouped.push(indices(r.u32s()?));
            }
        }
        // (NaN fails too.)
        if version >= 10 && grouped_error.partial_cmp(&error).is_none_or(|o| o.is_lt()) {
            return Err(r.err(format!("object {id}: a tile's level has a group error below its error")));
        }
        // Variants by group depth (versions 10, 11) mean nothing to today's stitching.
        let (grouped, grouped_error) = if version >= 12 { (grouped, grouped_error) } else { (Vec::new(), error) };
        levels.push(crate::lod::levels::Level {
            error,
            error_z,
            shading_error,
            indices: level_indices,
            grouped,
            grouped_error,
        });
    }
    let grouped = levels.iter().flat_map(|l| &l.grouped);
    for level in [&fine, &coarse].into_iter().chain(levels.iter().map(|l| &l.indices)).chain(grouped) {
        if level.len() % 3 != 0 || level.iter().any(|&k| k as usize >= positions.len()) {
            return Err(r.err(format!("object {id}: a tile's triangles index beyond its vertices")));
        }
    }
    // Before version 6 the shading error was not stored: measured again (meshes) or
    // 0 (height fields, grids), as `lod` sets it when building. From version 6 a NaN one is
    // damage (`check::tile` refuses it), not measured again (that takes some 80 bytes per vertex).
    for l in levels.iter_mut().filter(|l| version < 6 && l.shading_error.is_nan()) {
        l.shading_error = match kind {
            ObjectKind::Mesh { .. } => {
                let shading = crate::lod::shading::Shading { normals: &normals, grid_uv: &grid_uv };
                crate::lod::shading::shading_error(&positions, shading, &fine, &l.indices)
            }
            _ => 0.0,
        };
    }
    if levels.iter().any(|l| l.shading_error < 0.0) {
        return Err(r.err(format!("object {id}: a tile's level has a negative shading error")));
    }
    Ok(TileMesh {
        ix,
        iy,
        positions,
        values,
        normals,
        grid_uv,
        ring_z,
        stations,
        fine,
        coarse,
        bbox_min,
        bbox_max,
        proxy_error,
        levels: levels.into(),
    })
}

/// A triangle list as tiles hold it; an empty one allocates nothing (`Arc::default`), where
/// `Arc::from` an empty vector takes a 16-byte block: an empty tile read stays small (issue 39).
fn indices(v: Vec<u32>) -> crate::lod::Indices {
    if v.is_empty() {
        crate::lod::Indices::default()
    } else {
        v.into()
    }
}

#[cfg(test)]
#[path = "serial_tests.rs"]
mod tests;
