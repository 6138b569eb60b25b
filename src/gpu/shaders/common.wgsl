// Shared by the scene passes (prepended to draw.wgsl and prepass.wgsl, globals.wgsl before it): one vertex buffer of f32
// positions relative to their objects' origins, drawn with multi-draw-indirect where
// first_instance carries the global tile index. A lattice tile's vertices are (column, row, 0)
// of a shared pattern instead, turned into positions by tile_position. Every pass uses this one
// transform, so their depths agree.

struct Object {
    // Translation (world units) applied before exaggeration.
    offset: vec4<f32>,
    color: vec4<f32>,
    // Colour map (draw.wgsl): lo, 1 / (hi - lo), mode (0 flat, 1 vertex scalar, 2 z), its table.
    cmap: vec4<f32>,
    // A height field's normal map (draw.wgsl): object-relative (x, y) of sample (0, 0), then
    // (cos, sin) / dx: the column of a point; (-sin, cos) / dy: its row, then nx, ny (a grid
    // mesh's: its columns and rows).
    grid: vec4<f32>,
    grid_rows: vec4<f32>,
    // x: 1 + the object's first sample in the normal map, 0: none; y: 1 when its vertices carry
    // smooth normals, 2 when they carry grid coordinates (normals in the normal map: a grid
    // mesh), 3 cell coordinates (a reservoir grid coloured per cell); with neither, facet
    // normals; z: the depth-tie priority (priority_clip); w: 1 for a well whose vertices carry
    // their stations, its log a table (draw.wgsl log_scalar).
    normal_map: vec4<u32>,
}

// Per tile four texels (gpu::layout::tile_texels), 2048 tiles to a row: its grid (tile_grid_at),
// then its object.
@group(0) @binding(2) var tiles: texture_2d<u32>;

// Texel `i` (0..=3) of `tile` in `tiles`.
fn tile_texel(tile: u32, i: u32) -> vec4<u32> {
    return textureLoad(tiles, vec2<u32>((tile % 2048u) * 4u + i, tile / 2048u), 0);
}

// Vector `i` (0..=2) of `tile`'s grid (gpu::geometry::SceneGeometry::tiles): a lattice tile's
// first sample's object-relative (x, y) and the grid's column axis; its row axis, the first
// sample's index in `surface` and the grid's row length (u32 bits); the first sample's index in
// `sample_values` (draw.wgsl; 0xffffffff: none). 0xffffffff in place of the `surface` index for
// a tile with vertices of its own.
fn tile_grid_at(tile: u32, i: u32) -> vec4<f32> {
    return bitcast<vec4<f32>>(tile_texel(tile, i));
}

// The frame's objects (gpu::layout::object_texels): six texels an object, 1365 objects to a row.
// A texture, not storage: a CPU rasteriser gathers a texel fetch in one vector operation, where it
// loads storage lane by lane behind a branch.
@group(0) @binding(1) var objects: texture_2d<u32>;

// The object of `tile` (every vertex and fragment stage of the scene passes reads it so).
fn object_at(tile: u32) -> Object {
    let i = tile_texel(tile, 3u).x;
    let x = (i % 1365u) * 6u;
    let y = i / 1365u;
    return Object(bitcast<vec4<f32>>(textureLoad(objects, vec2<u32>(x, y), 0)),
                  bitcast<vec4<f32>>(textureLoad(objects, vec2<u32>(x + 1u, y), 0)),
                  bitcast<vec4<f32>>(textureLoad(objects, vec2<u32>(x + 2u, y), 0)),
                  bitcast<vec4<f32>>(textureLoad(objects, vec2<u32>(x + 3u, y), 0)),
                  bitcast<vec4<f32>>(textureLoad(objects, vec2<u32>(x + 4u, y), 0)),
                  textureLoad(objects, vec2<u32>(x + 5u, y), 0));
}

// Height fields' fine surfaces (scene::Object::shading_samples), object after object, 8192
// samples to a row (gpu::geometry::SHADING_ROW), per sample: the gradient (dz/dx, dz/dy) as two
// f16 (a grid mesh's packed fine normal), then the object-relative height (f32 bits).
@group(0) @binding(4) var surface: texture_2d<u32>;

// Sample `k` of `surface`: (gradients or normal, height bits).
fn surface_sample(k: u32) -> vec2<u32> {
    return textureLoad(surface, vec2<u32>(k % 8192u, k / 8192u), 0).xy;
}

// The object-relative position of vertex `pos` of `tile`: `pos` itself, or for a lattice tile the
// sample at column pos.x, row pos.y from the tile's first, with its height from `surface`.
fn tile_position(pos: vec3<f32>, tile: u32) -> vec3<f32> {
    let b = tile_grid_at(tile, 1u);
    let k0 = bitcast<u32>(b.z);
    if (k0 == 0xffffffffu) {
        return pos;
    }
    let a = tile_grid_at(tile, 0u);
    let k = k0 + u32(pos.y) * bitcast<u32>(b.w) + u32(pos.x);
    return vec3<f32>(a.xy + pos.x * a.zw + pos.y * b.xy, bitcast<f32>(surface_sample(k).y));
}

// Clip position `clip` of a vertex of object `o` with its depth-tie priority applied
// (scene::Object::priority, PRIORITY_DEPTH_STEP): as if the fraction (priority - 4) x 2^-21 of
// its distance nearer (priority.wgsl `nearer_by`; horizons, 4, exactly where they are), so that
// of two coincident surfaces the one of higher priority is seen whatever the draw order. Every
// scene pass applies it (the same expression everywhere: depths agree); the box tests take the
// largest priority (box_test.wgsl `nearest`).
fn priority_clip(clip: vec4<f32>, o: Object) -> vec4<f32> {
    return nearer_by(clip, (f32(o.normal_map.z) - 4.0) * PRIORITY_STEP);
}

struct VOut {
    // Invariant so that the depth prepass and later passes rasterise identical depth.
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) @interpolate(flat) tile: u32,
}

// How far a well tube's vertex is lowered before exaggeration (`rz`: its height above its ring's
// centre, lod::TileMesh::ring_z; 0 for every other vertex): by (1 - 1 / z_scale) rz, so that
// its ring's centre is exaggerated and its offset from it is not, and the tube keeps its radius
// however much z is exaggerated. Flattening (z_scale < 1) flattens tubes whole. Between the
// vertex and its ring's centre, so within its tile's box.
fn ring_lift(rz: f32) -> vec3<f32> {
    return vec3<f32>(0.0, 0.0, select(0.0, (1.0 - 1.0 / g.z_scale) * rz, g.z_scale > 1.0));
}

@vertex
fn vs_main(@location(0) vpos: vec3<f32>, @location(3) rz: f32, @builtin(instance_index) tile: u32) -> VOut {
    let o = object_at(tile);
    let p = (tile_position(vpos, tile) - ring_lift(rz) + o.offset.xyz) * vec3<f32>(1.0, 1.0, g.z_scale);
    var out: VOut;
    out.clip = priority_clip(g.view_proj * vec4<f32>(p, 1.0), o);
    out.world = p;
    out.tile = tile;
    return out;
}

// The GL variant (`*_gl` entry points, chosen by gpu::passes on the GL backend). wgpu's GL backend
// rewrites clip z to GL's [-1, 1] range (z' = 2z - w) and GL maps it back through the fixed depth
// range (0.5 z'/w + 0.5): both steps round near -1, keeping only ~2^-24 *absolute* precision of
// the reverse-Z depth near / distance (distances off by 12 % at 5 m with near 1e-6, layers 0.5 m
// apart z-fighting at 20 km). So the GL pipelines carry clip z and w to the fragment and write
// frag_depth = z / w, the value the other backends rasterise, with the float depth buffer's
// relative precision. (Writing frag_depth costs early depth tests, so other backends do not.) The
// GL entry points repeat vs_main's / fs_main's bodies rather than sharing helpers with them, so
// that the other backends' code is exactly what it was: a shared shading helper made lavapipe's
// lit pass ~12 % slower.
struct VOutGl {
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) @interpolate(flat) tile: u32,
    @location(2) zw: vec2<f32>,
}

// The same transform as vs_main (kept apart so that vs_main's code is what it always was).
@vertex
fn vs_gl(@location(0) vpos: vec3<f32>, @location(3) rz: f32, @builtin(instance_index) tile: u32) -> VOutGl {
    let o = object_at(tile);
    let p = (tile_position(vpos, tile) - ring_lift(rz) + o.offset.xyz) * vec3<f32>(1.0, 1.0, g.z_scale);
    let clip = priority_clip(g.view_proj * vec4<f32>(p, 1.0), o);
    return VOutGl(clip, p, tile, clip.zw);
}

fn gl_depth(v: VOutGl) -> f32 {
    return v.zw.x / v.zw.y;
}
