//! Untrusted bytes allocate at most about twice their size (issue 39): `Scene::from_bytes` and
//! `Volume::from_bytes` of valid and tampered byte strings, and cameras from tampered arguments
//! (a camera pickles as `Camera::look_at`'s arguments; there is no camera byte format), each
//! measured by a counting global allocator: the peak of the bytes it held at once during the call,
//! beyond what was allocated before it, must be at most `2 * input + SLACK`, in every case: no
//! exception, valid scenes of every size (large height fields, height fields of the smallest
//! tiles) and scenes made only of the smallest records (empty objects and tiles) included. Every
//! case returns Ok or an Err; none panics.
//!
//! Loading builds no slabs (`lod::slab`: a height field's are not stored, and are rebuilt from its
//! tiles when a renderer first needs them, `Object::slabs`). They are built here after each scene
//! that loads, outside the measurement, and their bytes checked against [`SLAB_FACTOR`] times the
//! input: they are built only from tiles whose vertices are distinct samples of their grid (a
//! tile's lattice has at most 4 samples per vertex + 64).
//!
//! Cases (about 45,000, deterministic; counts by kind printed with `--nocapture`): valid scenes of
//! every kind (height fields plain, rotated and yflipped, with holes, coloured by values; meshes,
//! structured and not; a well, a slice, a lens, a grid), each alone and all together, and every
//! integer field of theirs (every object and tile) and every float and first and last array
//! element (of each object and its first tile) at boundary values (0, 1, 2, one off, 2^16, 2^31,
//! 2^32 - 1, 2^32, 2^40, 2^63, u64::MAX, and for counts what the rest of the buffer holds, half
//! that and one more; NaN, infinities, -0, -1, huge, denormal), truncations (the first 1,500
//! lengths and 300 more) and random bit flips; large valid height fields (up to 200 x 150) with
//! their integers so tampered; height fields of 20,000 tiles of 2 x 2 and 3 x 3 samples, valid
//! and truncated; scenes of up to 20,000 empty objects or tiles; volumes likewise; camera
//! arguments likewise.
//!
//! Bytes of the current format (version 9, what `to_bytes` writes), and the smallest records of
//! every older one (an empty object takes 54 bytes in versions 1 and 2, an empty tile 64 in
//! versions 1 to 3, for the same structs): those claim half a struct each, so that scenes made
//! only of them are refused or held within twice their size too.
//!
//! Its own test binary (for the `#[global_allocator]`), one `#[test]`: the counters are global
//! and armed only around one call at a time (any thread's allocations count while armed).

use std::alloc::{GlobalAlloc, Layout, System};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicIsize, Ordering::SeqCst};
use std::sync::Arc;

use geocull::{AddOptions, Camera, ColorByArg, GridFrame, LensSlice, Projection, Scene, Volume};

// ------------------------------------------------------------------------ counting allocator

struct Counting;

static ARMED: AtomicBool = AtomicBool::new(false);
static CUR: AtomicIsize = AtomicIsize::new(0);
static PEAK: AtomicIsize = AtomicIsize::new(0);

fn grew(n: usize) {
    if ARMED.load(SeqCst) {
        let c = CUR.fetch_add(n as isize, SeqCst) + n as isize;
        PEAK.fetch_max(c, SeqCst);
    }
}

fn shrank(n: usize) {
    if ARMED.load(SeqCst) {
        CUR.fetch_sub(n as isize, SeqCst);
    }
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(l) };
        if !p.is_null() {
            grew(l.size());
        }
        p
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(l) };
        if !p.is_null() {
            grew(l.size());
        }
        p
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) };
        shrank(l.size());
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, new: usize) -> *mut u8 {
        let q = unsafe { System.realloc(p, l, new) };
        if !q.is_null() {
            // Both blocks may be live at once (a moving realloc): counted so.
            grew(new);
            shrank(l.size());
        }
        q
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Bytes every call may take besides twice its input: error messages (formatted once on the way
/// out: up to some 1.3 KB for a camera) and the checks' temporaries for one small tile
/// (`serial::check`: a height field tile's samples). Measured: at most 1.1 KB over twice the
/// input (a camera's message; 0.2 KB for scenes and volumes).
const SLACK: usize = 4 << 10;

/// The slabs a loaded scene's first frame builds (`Object::slabs`, not loading), per byte of its
/// input: a slab's prisms take some 80 bytes per sample of a tile's lattice (vertices of 16 bytes
/// top and bottom, triangles) against some 40 bytes a sample takes in the buffer (position, fine,
/// coarse and level triangles). Measured: 4.4 (a 200 x 150 height field, counting the vectors'
/// spare capacity).
const SLAB_FACTOR: usize = 6;

/// `f`'s outcome and the peak of the bytes allocated at once while it ran (beyond those before).
fn measured<T>(f: impl FnOnce() -> T) -> (T, usize) {
    CUR.store(0, SeqCst);
    PEAK.store(0, SeqCst);
    ARMED.store(true, SeqCst);
    let out = f();
    ARMED.store(false, SeqCst);
    (out, PEAK.load(SeqCst).max(0) as usize)
}

// ------------------------------------------------------------------------------ byte layouts

#[derive(Clone, Copy, Debug, PartialEq)]
enum Ty {
    U8,
    U32,
    U64,
    F32,
    F64,
}

impl Ty {
    fn size(self) -> usize {
        match self {
            Ty::U8 => 1,
            Ty::U32 | Ty::F32 => 4,
            Ty::U64 | Ty::F64 => 8,
        }
    }
}

/// One scalar field of a byte string: its offset and type, and for an array count the size of
/// its elements (to set it to what the rest of the buffer holds).
#[derive(Clone, Debug)]
struct Field {
    name: String,
    at: usize,
    ty: Ty,
    elem: Option<usize>,
}

/// Walks bytes as the core's reader does, noting each field.
struct Walk<'a> {
    b: &'a [u8],
    pos: usize,
    out: Vec<Field>,
    /// Whether floats and array elements are noted (ints and counts always are).
    all: bool,
}

impl Walk<'_> {
    fn get(&mut self, name: &str, ty: Ty) -> u64 {
        let s = &self.b[self.pos..self.pos + ty.size()];
        let v = match ty {
            Ty::U8 => s[0] as u64,
            Ty::U32 | Ty::F32 => u32::from_le_bytes(s.try_into().unwrap()) as u64,
            Ty::U64 | Ty::F64 => u64::from_le_bytes(s.try_into().unwrap()),
        };
        if self.all || matches!(ty, Ty::U8 | Ty::U32 | Ty::U64) {
            self.out.push(Field { name: name.into(), at: self.pos, ty, elem: None });
        }
        self.pos += ty.size();
        v
    }
    fn str(&mut self, name: &str) {
        let n = self.get(&format!("{name}.len"), Ty::U32) as usize;
        self.out.last_mut().unwrap().elem = Some(1);
        self.pos += n;
    }
    /// An array: its count, and (when `all`) its first and last elements.
    fn arr(&mut self, name: &str, ty: Ty) {
        let n = self.get(&format!("{name}.count"), Ty::U64) as usize;
        self.out.last_mut().unwrap().elem = Some(ty.size());
        if self.all && n > 0 {
            for k in [0, n - 1] {
                self.out.push(Field { name: format!("{name}[{k}]"), at: self.pos + k * ty.size(), ty, elem: None });
            }
        }
        self.pos += n * ty.size();
    }
    fn levels(&mut self, name: &str) {
        let n = self.get(&format!("{name}.n_levels"), Ty::U32);
        for v in 0..n {
            for k in ["cells", "faces", "triangles", "vertices"] {
                self.get(&format!("{name}.level{v}.{k}"), Ty::U64);
            }
            self.get(&format!("{name}.level{v}.volume"), Ty::F64);
            self.get(&format!("{name}.level{v}.interior_triangles"), Ty::U64);
        }
    }
}

/// The fields of scene bytes, version 12 (src/scene/serial.rs's module docs): every integer of
/// every object and tile; floats and array elements of each object and its first tile.
fn scene_fields(b: &[u8]) -> Vec<Field> {
    assert_eq!(&b[..8], b"GCSCENE\0");
    let mut p = Walk { b, pos: 8, out: Vec::new(), all: true };
    assert_eq!(p.get("version", Ty::U32), 12, "the scene format changed: update scene_fields");
    p.get("has_origin", Ty::U8);
    for a in "xyz".chars() {
        p.get(&format!("origin.{a}"), Ty::F64);
    }
    p.get("next_id", Ty::U32);
    let n = p.get("n_objects", Ty::U32);
    for o in 0..n {
        p.all = true;
        let pre = format!("obj{o}");
        p.get(&format!("{pre}.id"), Ty::U32);
        p.str(&format!("{pre}.name"));
        match p.get(&format!("{pre}.kind"), Ty::U8) {
            0 => {
                for k in ["nx", "ny"] {
                    p.get(&format!("{pre}.hf.{k}"), Ty::U64);
                }
                for k in ["x0", "y0", "dx", "dy", "rotation"] {
                    p.get(&format!("{pre}.hf.{k}"), Ty::F64);
                }
                for k in ["tx", "ty"] {
                    p.get(&format!("{pre}.hf.{k}"), Ty::U64);
                }
            }
            1 => p.str(&format!("{pre}.mesh.label")),
            2 => {
                for k in ["nk", "nj", "ni", "bi", "bj"] {
                    p.get(&format!("{pre}.grid.{k}"), Ty::U64);
                }
                p.arr(&format!("{pre}.grid.cell_size"), Ty::F32);
                p.levels(&format!("{pre}.grid"));
                let nb = p.get(&format!("{pre}.grid.n_blocks"), Ty::U32);
                for k in 0..nb {
                    p.levels(&format!("{pre}.grid.block{k}"));
                }
            }
            k => panic!("kind {k}"),
        }
        for c in "rgb".chars() {
            p.get(&format!("{pre}.color.{c}"), Ty::F32);
        }
        p.get(&format!("{pre}.visible"), Ty::U8);
        for k in ["offset", "origin"] {
            for a in "xyz".chars() {
                p.get(&format!("{pre}.{k}.{a}"), Ty::F64);
            }
        }
        if p.get(&format!("{pre}.color_by"), Ty::U8) != 0 {
            p.str(&format!("{pre}.cmap"));
            p.arr(&format!("{pre}.lut"), Ty::F32);
            p.get(&format!("{pre}.clim.lo"), Ty::F64);
            p.get(&format!("{pre}.clim.hi"), Ty::F64);
            for c in "rgb".chars() {
                p.get(&format!("{pre}.nan_color.{c}"), Ty::F32);
            }
        }
        p.get(&format!("{pre}.opacity"), Ty::F32);
        p.get(&format!("{pre}.priority"), Ty::U8);
        let nt = p.get(&format!("{pre}.n_tiles"), Ty::U32);
        for t in 0..nt {
            p.all = t == 0;
            let q = format!("{pre}.tile{t}");
            p.get(&format!("{q}.ix"), Ty::U32);
            p.get(&format!("{q}.iy"), Ty::U32);
            for k in ["bbox_min", "bbox_max"] {
                for a in "xyz".chars() {
                    p.get(&format!("{q}.{k}.{a}"), Ty::F32);
                }
            }
            p.arr(&format!("{q}.positions"), Ty::F32);
            p.arr(&format!("{q}.values"), Ty::F32);
            for k in ["normals", "grid_uv"] {
                p.arr(&format!("{q}.{k}"), Ty::U32);
            }
            p.arr(&format!("{q}.ring_z"), Ty::F32);
            p.arr(&format!("{q}.stations"), Ty::F32);
            for k in ["fine", "coarse"] {
                p.arr(&format!("{q}.{k}"), Ty::U32);
            }
            p.get(&format!("{q}.proxy_error"), Ty::F32);
            let nl = p.get(&format!("{q}.n_levels"), Ty::U32);
            for v in 0..nl {
                p.get(&format!("{q}.level{v}.error"), Ty::F32);
                p.get(&format!("{q}.level{v}.shading_error"), Ty::F32);
                p.get(&format!("{q}.level{v}.error_z"), Ty::F32);
                p.arr(&format!("{q}.level{v}.indices"), Ty::U32);
                p.get(&format!("{q}.level{v}.grouped_error"), Ty::F32);
                for d in 0..p.get(&format!("{q}.level{v}.n_grouped"), Ty::U32) {
                    p.arr(&format!("{q}.level{v}.grouped{d}"), Ty::U32);
                }
            }
        }
    }
    assert_eq!(p.pos, b.len());
    p.out
}

/// The fields of volume bytes, version 2 (`Volume::to_bytes`).
fn volume_fields(b: &[u8]) -> Vec<Field> {
    assert_eq!(&b[..8], b"GCVOLUM\0");
    let mut p = Walk { b, pos: 8, out: Vec::new(), all: true };
    assert_eq!(p.get("version", Ty::U32), 2, "the volume format changed: update volume_fields");
    for k in ["nx", "ny", "nz"] {
        p.get(k, Ty::U64);
    }
    for k in ["origin.x", "origin.y", "origin.z", "spacing.x", "spacing.y", "spacing.z", "offset", "rotation"] {
        p.get(k, Ty::F64);
    }
    p.arr("residuals", Ty::F32);
    assert_eq!(p.pos, b.len());
    p.out
}

fn read(b: &[u8], f: &Field) -> u64 {
    let s = &b[f.at..f.at + f.ty.size()];
    let mut a = [0u8; 8];
    a[..s.len()].copy_from_slice(s);
    u64::from_le_bytes(a)
}

fn put(b: &[u8], f: &Field, bits: u64) -> Vec<u8> {
    let mut v = b.to_vec();
    v[f.at..f.at + f.ty.size()].copy_from_slice(&bits.to_le_bytes()[..f.ty.size()]);
    v
}

/// Boundary values (as bits) of a field's type: counts also set to what the rest of the buffer
/// holds (and one more), so that a count that passes the reader's check is tried too.
fn values(b: &[u8], f: &Field) -> Vec<u64> {
    let orig = read(b, f);
    let mut v: Vec<u64> = match f.ty {
        Ty::U8 => vec![0, 1, 2, 255],
        Ty::U32 => vec![0, 1, 2, orig.wrapping_sub(1), orig + 1, 1 << 16, 1 << 31, u32::MAX as u64],
        Ty::U64 => {
            vec![0, 1, 2, orig.wrapping_sub(1), orig + 1, 1 << 31, u32::MAX as u64, 1 << 32, 1 << 40, 1 << 63, u64::MAX]
        }
        Ty::F32 => [
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            -0.0,
            -1.0,
            3.4e38,
            1e-45,
            f32::from_bits(orig as u32) * 2.0 + 1.0,
        ]
        .iter()
        .map(|x| x.to_bits() as u64)
        .collect(),
        Ty::F64 => [
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            -0.0,
            -1.0,
            1e300,
            5e-324,
            1e13,
            f64::from_bits(orig) * 2.0 + 1.0,
        ]
        .iter()
        .map(|x| x.to_bits())
        .collect(),
    };
    if let Some(e) = f.elem {
        let rest = (b.len() - f.at - f.ty.size()) as u64 / e as u64;
        v.extend([rest, rest + 1, rest / 2]);
    }
    let top = if f.ty.size() == 8 { u64::MAX } else { (1u64 << (8 * f.ty.size())) - 1 };
    v.retain(|&x| x != orig && x <= top);
    v.sort_unstable();
    v.dedup();
    v
}

// ------------------------------------------------------------------------------- originals

fn opts(name: &str) -> AddOptions {
    AddOptions { name: Some(name.into()), ..AddOptions::new(2.0) }
}

/// A cheap deterministic generator (xorshift64*).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn ball_volume() -> Volume {
    let n = 6;
    let c = |i: usize| -1.0 + 2.0 * i as f64 / (n - 1) as f64;
    let v: Vec<f32> = (0..n * n * n)
        .map(|k| 100.0 + (c(k % n).powi(2) + c(k / n % n).powi(2) + c(k / n / n).powi(2)).sqrt() as f32)
        .collect();
    Volume::new(v.into(), (n, n, n), [12.0, 22.0, -6.0], [0.8; 3]).unwrap().with_rotation(10.0).unwrap()
}

fn heightfield(s: &mut Scene, rot: f64, yflip: bool, tiles: (usize, usize), values: bool, name: &str) {
    let (nx, ny) = (23, 17);
    let z: Vec<f64> = (0..nx * ny)
        .map(|k| {
            if k % 37 == 5 || k == 100 {
                f64::NAN
            } else {
                ((k % nx) as f64 * 0.4).sin() * 3.0 + (k / nx) as f64 * 0.2
            }
        })
        .collect();
    let frame = GridFrame::new([10.0, 20.0], [1.0, 1.5]).rotated(rot, yflip);
    let mut o = opts(name);
    if values {
        o.color_by = Some(ColorByArg::values(z.iter().map(|v| v * 2.0).collect()));
    }
    s.add_heightfield(&z, ny, nx, frame, tiles, None, o).unwrap();
}

fn mesh(s: &mut Scene) {
    // A structured sheet (grid coordinates, smooth normals) in 2 tiles, coloured by values.
    let n = 12;
    let v: Vec<[f64; 3]> = (0..n * n)
        .map(|k| [10.0 + (k % n) as f64, 20.0 + (k / n) as f64, ((k % n) as f64 * 0.5).sin() * 2.0])
        .collect();
    let mut f = Vec::new();
    for j in 0..n as i64 - 1 {
        for i in 0..n as i64 - 1 {
            let a = j * n as i64 + i;
            f.extend([[a, a + 1, a + n as i64 + 1], [a, a + n as i64 + 1, a + n as i64]]);
        }
    }
    let mut o = opts("sheet");
    o.color_by = Some(ColorByArg::values(v.iter().map(|p| p[0]).collect()));
    s.add_mesh(&v, &f, "fault", Some(2), o).unwrap();
    // A random mesh (no structure).
    let mut r = Rng(7);
    let v: Vec<[f64; 3]> =
        (0..30).map(|_| [10.0 + 10.0 * r.unit(), 20.0 + 10.0 * r.unit(), -2.0 + 4.0 * r.unit()]).collect();
    let f: Vec<[i64; 3]> = (0..40).map(|_| [r.below(30) as i64, r.below(30) as i64, r.below(30) as i64]).collect();
    s.add_mesh(&v, &f, "fault", None, opts("random")).unwrap();
}

fn well(s: &mut Scene) {
    s.add_well(&[[14.0, 24.0, 3.0], [15.0, 25.0, -3.0], [16.0, 24.0, -8.0]], 0.3, 5, opts("well")).unwrap();
}

fn grid(s: &mut Scene, values: bool) {
    let (nk, nj, ni) = (2, 2, 3);
    let mut corners = Vec::new();
    for k in 0..nk {
        for j in 0..nj {
            for i in 0..ni {
                for q in 0..8 {
                    corners.extend([
                        18.0 + (i + (q & 1)) as f64,
                        20.0 + (j + ((q >> 1) & 1)) as f64,
                        -((k + ((q >> 2) & 1)) as f64),
                    ]);
                }
            }
        }
    }
    let mut o = opts("grid");
    if values {
        o.color_by = Some(ColorByArg::values((0..nk * nj * ni).map(|c| c as f64 * 0.3).collect()));
    }
    s.add_grid((nk, nj, ni), &corners, None, None, (2, 1), o).unwrap();
}

fn slice(s: &mut Scene, v: &Volume) {
    let (pos, vals, (nu, nv)) = v.plane(0, 2, [(0, 5), (0, 5), (0, 5)]);
    s.add_lattice(&pos, vals, (nu, nv), "slice", opts("slice")).unwrap();
}

fn lens(s: &mut Scene, v: &Volume) {
    let slices = (0..3)
        .map(|axis| {
            let (positions, values, (nu, nv)) = v.plane(axis, 3, [(0, 3), (1, 4), (0, 5)]);
            LensSlice { axis: axis as u32, index: 3, positions, values, nu, nv }
        })
        .collect();
    s.add_lens(slices, 0.5, opts("lens")).unwrap();
}

/// Valid scenes: one of every kind together, and each kind alone.
fn scenes() -> Vec<(&'static str, Vec<u8>)> {
    let vol = ball_volume();
    let mut all = Scene::new();
    heightfield(&mut all, 0.0, false, (2, 2), false, "h");
    heightfield(&mut all, 30.0, true, (3, 2), true, "turned");
    mesh(&mut all);
    well(&mut all);
    slice(&mut all, &vol);
    lens(&mut all, &vol);
    grid(&mut all, true);
    let one = |f: &dyn Fn(&mut Scene)| {
        let mut s = Scene::new();
        f(&mut s);
        s.to_bytes()
    };
    vec![
        ("all", all.to_bytes()),
        ("heightfield", one(&|s| heightfield(s, 0.0, false, (1, 1), false, "h"))),
        ("heightfield rotated", one(&|s| heightfield(s, -137.2, true, (4, 3), true, "turned"))),
        ("mesh", one(&mesh)),
        ("well", one(&well)),
        ("grid", one(&|s| grid(s, false))),
        ("slice", one(&|s| slice(s, &vol))),
        ("lens", one(&|s| lens(s, &vol))),
        ("empty", Scene::new().to_bytes()),
    ]
}

/// Scene bytes of format `version` of `objects` meshes with no name, label nor tiles, then one
/// with `tiles` empty tiles: the smallest records there are (84 and 88 bytes in the current
/// format, 54 and 64 in version 1), each held in a larger struct.
fn tiny_records(version: u32, objects: u32, tiles: u32) -> Vec<u8> {
    let mut b = Scene::new().to_bytes();
    b.truncate(b.len() - 8);
    b[8..12].copy_from_slice(&version.to_le_bytes());
    b.extend((objects + 1).to_le_bytes()); // next_id
    b.extend((objects + 1).to_le_bytes()); // n_objects
    for id in 0..=objects {
        b.extend(id.to_le_bytes());
        b.extend([0; 4]); // name
        b.push(1); // a mesh
        b.extend([0; 4]); // label
        b.extend([0.5f32; 3].iter().flat_map(|c| c.to_le_bytes()));
        b.push(1); // visible
        b.extend([0; 24]); // offset
        if version >= 3 {
            b.extend([0; 24]); // origin
        }
        if version >= 4 {
            b.push(0); // flat
            b.extend(1.0f32.to_le_bytes());
        }
        if version >= 7 {
            b.push(255); // priority by kind
        }
        let n = if id == objects { tiles } else { 0 };
        b.extend(n.to_le_bytes());
        // Empty arrays: positions, values (version 4), normals (5), grid coordinates (6), ring
        // heights (9), fine and coarse triangles.
        let arrays = 3 + [4, 5, 6, 9].iter().filter(|&&v| version >= v).count();
        for _ in 0..n {
            // ix, iy, box, the empty arrays, proxy error, no levels
            b.extend(vec![0; 8 + 24 + arrays * 8 + 4 + 4]);
        }
    }
    b
}

// ------------------------------------------------------------------------------------ cases

#[derive(Default, Debug)]
struct Tally {
    cases: usize,
    ok: usize,
    err: usize,
    panics: Vec<String>,
    over: Vec<String>,
    /// Whether every case's peak is printed (else only those of valid inputs).
    print_all: bool,
    /// The largest peak / input, and its case.
    worst: (f64, String),
    /// The largest peak / input of inputs of 4 KiB or more, and its case.
    worst_large: (f64, String),
    /// The largest peak - 2 * input, and its case.
    worst_excess: (isize, String),
    /// The largest slab bytes / input built after loading (not measured), and its case.
    slabs: (f64, String),
}

impl Tally {
    /// Runs one case, `f` (Ok or an Err), and checks its peak against `2 * input + SLACK`.
    /// Returns what `f` gave when Ok (dropped by the caller, after the measurement).
    fn run<T>(&mut self, name: &str, input: usize, f: impl FnOnce() -> Result<T, String>) -> Option<T> {
        let (out, peak) = measured(|| catch_unwind(AssertUnwindSafe(f)));
        self.cases += 1;
        let kept = match out {
            Ok(Ok(v)) => {
                self.ok += 1;
                Some(v)
            }
            Ok(Err(_)) => {
                self.err += 1;
                None
            }
            Err(_) => {
                self.panics.push(name.into());
                None
            }
        };
        let ratio = peak as f64 / input.max(1) as f64;
        if input >= 4096 && ratio > self.worst_large.0 {
            self.worst_large = (ratio, format!("{name}: {peak} bytes for {input}"));
        }
        if ratio > self.worst.0 {
            self.worst = (ratio, format!("{name}: {peak} bytes for {input}"));
        }
        let excess = peak as isize - 2 * input as isize;
        if excess > self.worst_excess.0 {
            self.worst_excess = (excess, format!("{name}: {peak} bytes for {input}"));
        }
        if name.ends_with("valid") || self.print_all {
            eprintln!("{name}: {peak} bytes for {input} ({ratio:.3})");
        }
        if peak > 2 * input + SLACK {
            self.over.push(format!("{name}: {peak} bytes for {input}"));
        }
        kept
    }

    /// Builds a loaded scene's slabs (as its first frame does; not measured) and checks their
    /// bytes against [`SLAB_FACTOR`] times the input.
    fn slabs(&mut self, name: &str, input: usize, s: &Scene) {
        let slabs = s.objects().iter().flat_map(|o| o.slabs()).flatten();
        let bytes: usize = slabs.map(|s| 16 * s.vertices.capacity() + 4 * s.indices.capacity()).sum();
        if bytes > SLAB_FACTOR * input + SLACK {
            self.over.push(format!("{name}: {bytes} bytes of slabs for {input}"));
        }
        let per = bytes as f64 / input.max(1) as f64;
        if per > self.slabs.0 {
            self.slabs = (per, name.into());
        }
    }
}

fn scene_case(t: &mut Tally, name: &str, b: &[u8]) {
    if let Some(s) = t.run(name, b.len(), || Scene::from_bytes(b).map_err(|e| e.to_string())) {
        t.slabs(name, b.len(), &s);
    }
}

fn volume_case(t: &mut Tally, name: &str, b: &[u8]) {
    t.run(name, b.len(), || Volume::from_bytes(b).map(|_| ()).map_err(|e| e.to_string()));
}

/// Tampered copies of `b` (fields at boundary values, truncations, bit flips), each passed to `f`.
fn tampered(b: &[u8], fields: &[Field], flips: usize, seed: u64, mut f: impl FnMut(String, &[u8])) {
    for fl in fields {
        for v in values(b, fl) {
            f(format!("{}={v:#x}", fl.name), &put(b, fl, v));
        }
    }
    let mut r = Rng(seed);
    let n = b.len();
    let mut cuts: Vec<usize> = (0..n.min(1500)).chain((0..300).map(|_| r.below(n))).collect();
    cuts.sort_unstable();
    cuts.dedup();
    for k in cuts {
        f(format!("truncated to {k} of {n}"), &b[..k]);
    }
    for k in 0..flips {
        let mut t = b.to_vec();
        let mut bits = Vec::new();
        for _ in 0..1 + k % 3 {
            let bit = r.below(8 * n);
            t[bit / 8] ^= 1 << (bit % 8);
            bits.push(bit);
        }
        f(format!("bits {bits:?} flipped"), &t);
    }
}

/// A camera's `look_at` arguments as bytes (the fields a camera pickles): eye, target, up,
/// fov_y, near, far (NaN = None), ortho_height (NaN = None), z_scale (f64 each), the projection's
/// name (the rest, UTF-8).
fn camera_bytes() -> Vec<u8> {
    let mut b = Vec::new();
    for v in [2.0, 5.0, 14.0, 15.0, 24.0, -2.0, 0.0, 0.0, 1.0, 50.0, f64::NAN, 300.0, f64::NAN, 1.5] {
        b.extend(v.to_le_bytes());
    }
    b.extend(b"perspective");
    b
}

fn camera_from(b: &[u8]) -> Result<(), String> {
    if b.len() < 14 * 8 {
        return Err("truncated".into());
    }
    let f = |k: usize| f64::from_le_bytes(b[8 * k..8 * k + 8].try_into().unwrap());
    let opt = |k: usize| Some(f(k)).filter(|v| !v.is_nan());
    let p = std::str::from_utf8(&b[14 * 8..]).map_err(|_| "not UTF-8".to_string())?;
    let p = Projection::parse(p).map_err(|e| e.to_string())?;
    Camera::look_at(
        [f(0), f(1), f(2)],
        [f(3), f(4), f(5)],
        [f(6), f(7), f(8)],
        f(9),
        opt(10),
        opt(11),
        p,
        opt(12),
        f(13),
    )
    .map(|_| ())
    .map_err(|e| e.to_string())
}

#[test]
fn untrusted_bytes_allocate_at_most_twice_their_size() {
    let t0 = std::time::Instant::now();
    // Warm-up (rayon's pool, lazy statics): outside any measurement.
    let originals = scenes();
    for (name, b) in &originals {
        Scene::from_bytes(b).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    let vol = ball_volume().to_bytes();
    Volume::from_bytes(&vol).unwrap();
    let mut by_kind = Vec::new();

    let mut scene = Tally::default();
    for (k, (kind, b)) in originals.iter().enumerate() {
        let before = scene.cases;
        scene_case(&mut scene, &format!("{kind}: valid"), b);
        let fields = scene_fields(b);
        // The scene of every kind: 1500 bit flips; each kind alone: 300.
        let flips = if k == 0 { 1500 } else { 300 };
        tampered(b, &fields, flips, 39 + k as u64, |name, t| scene_case(&mut scene, &format!("{kind}: {name}"), t));
        by_kind.push((format!("scene {kind}"), scene.cases - before));
    }
    // Valid scenes of every size the kinds come in: the ratio of what loading keeps to the input.
    for (nx, ny, tiles) in [(2, 2, (1, 1)), (3, 9, (2, 4)), (64, 48, (3, 2)), (200, 150, (8, 6))] {
        let z: Vec<f64> = (0..nx * ny).map(|k| if k % 13 == 4 { f64::NAN } else { (k as f64 * 0.1).sin() }).collect();
        let mut s = Scene::new();
        s.add_heightfield(
            &z,
            ny,
            nx,
            GridFrame::new([5e5, 6e6], [25.0, 25.0]).rotated(12.0, true),
            tiles,
            None,
            opts("h"),
        )
        .unwrap();
        let b = s.to_bytes();
        let kind = format!("heightfield {nx} x {ny}");
        let before = scene.cases;
        scene_case(&mut scene, &format!("{kind}: valid"), &b);
        // Its integers (counts, sizes, ids) at boundary values, truncations.
        let ints: Vec<Field> = scene_fields(&b).into_iter().filter(|f| matches!(f.ty, Ty::U32 | Ty::U64)).collect();
        tampered(&b, &ints, 0, nx as u64, |name, t| scene_case(&mut scene, &format!("{kind}: {name}"), t));
        by_kind.push((format!("scene {kind}"), scene.cases - before));
    }
    // Height fields of the smallest tiles (2 x 2 and 3 x 3 samples, the second with rows of
    // holes): 20,000 tiles, nearly every vertex on a tile's border (`serial::check` compares the
    // heights tiles give a border sample). Valid, and cut at 19 lengths.
    for (nx, ny, holes) in [(201, 101, false), (401, 201, true)] {
        let z: Vec<f64> =
            (0..nx * ny).map(|k| if holes && (k / nx) % 4 >= 2 { f64::NAN } else { (k as f64 * 0.37).sin() }).collect();
        let mut s = Scene::new();
        s.add_heightfield(&z, ny, nx, GridFrame::new([5e5, 6e6], [25.0, 25.0]), (200, 100), None, opts("h")).unwrap();
        let b = s.to_bytes();
        let kind = format!("heightfield {nx} x {ny} in 200 x 100 tiles");
        let before = scene.cases;
        scene_case(&mut scene, &format!("{kind}: valid"), &b);
        for k in 1..20 {
            let n = b.len() * k / 20;
            scene_case(&mut scene, &format!("{kind}: truncated to {n} of {}", b.len()), &b[..n]);
        }
        by_kind.push((format!("scene {kind}"), scene.cases - before));
    }

    // The smallest records: what a struct holds beyond its bytes (not a count read unchecked).
    let mut tiny = Tally { print_all: true, ..Tally::default() };
    for (objects, tiles) in [(0, 1), (1, 0), (1000, 0), (0, 1000), (20_000, 0), (0, 20_000), (5000, 5000)] {
        // The current format's load; older ones' smaller records may be refused (a writer never
        // made them: every object it wrote had tiles, every tile vertices), never held beyond
        // twice their bytes.
        for version in 1..=9 {
            let b = tiny_records(version, objects, tiles);
            let loaded = Scene::from_bytes(&b);
            if version == 9 || loaded.is_ok() {
                let s = loaded.unwrap();
                assert_eq!(
                    (s.objects().len(), s.objects().last().unwrap().tiles.len()),
                    (objects as usize + 1, tiles as usize)
                );
            }
            tiny.run(&format!("version {version}: {objects} objects, {tiles} tiles"), b.len(), || {
                Scene::from_bytes(&b).map_err(|e| e.to_string())
            });
        }
    }
    by_kind.push(("scene tiny records".into(), tiny.cases));

    let mut volume = Tally::default();
    volume_case(&mut volume, "valid", &vol);
    tampered(&vol, &volume_fields(&vol), 300, 40, |name, t| volume_case(&mut volume, &name, t));
    for n in [2, 3, 17, 64] {
        let v = Volume::new(Arc::from(vec![1.5f32; n * n * n]), (n, n, n), [0.0; 3], [1.0; 3]).unwrap();
        volume_case(&mut volume, &format!("{n}^3: valid"), &v.to_bytes());
    }
    by_kind.push(("volume".into(), volume.cases));

    let mut camera = Tally::default();
    let cam = camera_bytes();
    camera.run("valid", cam.len(), || camera_from(&cam));
    assert_eq!(camera.ok, 1);
    let fields: Vec<Field> =
        (0..14).map(|k| Field { name: format!("arg{k}"), at: 8 * k, ty: Ty::F64, elem: None }).collect();
    tampered(&cam, &fields, 300, 41, |name, t| {
        camera.run(&name, t.len(), || camera_from(t));
    });
    for p in ["", "Perspective", "orthographic", "perspective\0", "\u{1F600}"] {
        let b = [&cam[..14 * 8], p.as_bytes()].concat();
        camera.run(&format!("projection {p:?}"), b.len(), || camera_from(&b));
    }
    by_kind.push(("camera".into(), camera.cases));

    let total = scene.cases + tiny.cases + volume.cases + camera.cases;
    eprintln!("cases by kind: {by_kind:?}; {total} in all, {:.1} s", t0.elapsed().as_secs_f64());
    for (what, t) in [("scene", &scene), ("scene tiny records", &tiny), ("volume", &volume), ("camera", &camera)] {
        eprintln!(
            "{what}: {} cases, {} Ok, {} Err, {} panics; worst peak/input {:.3} ({}), of inputs >= 4 KiB {:.3} ({}); \
             worst peak - 2 x input {} ({}); slabs built after loading / input at most {:.3} ({})",
            t.cases,
            t.ok,
            t.err,
            t.panics.len(),
            t.worst.0,
            t.worst.1,
            t.worst_large.0,
            t.worst_large.1,
            t.worst_excess.0,
            t.worst_excess.1,
            t.slabs.0,
            t.slabs.1
        );
        assert!(t.panics.is_empty(), "{what}: {} panics: {:?}", t.panics.len(), &t.panics[..t.panics.len().min(20)]);
        assert!(
            t.over.is_empty(),
            "{what}: {} cases over the bound (+ {SLACK}): {:?}",
            t.over.len(),
            &t.over[..t.over.len().min(20)]
        );
    }
    assert!(total >= 5000, "{total}");
}
