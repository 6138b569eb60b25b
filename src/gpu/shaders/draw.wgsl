// The lit pass: colour and tile id of the front-most fine surface (common.wgsl is prepended).
// Its vertex entry points are vs_main / vs_gl's transform, word for word (so that depths agree
// with the prepass), plus the vertex's scalar for colour by data.

// Colour maps of this frame's objects (gpu::layout::ColorTables): tables of 256 rows, then the
// NaN colour, 31 side by side in each row of the texture.
@group(0) @binding(3) var lut: texture_2d<f32>;

// Row `row` (0..=256) of colour-map table `table`.
fn lut_row(table: u32, row: u32) -> vec3<f32> {
    return textureLoad(lut, vec2<u32>((table % 31u) * 257u + row, table / 31u), 0).rgb;
}

// Height fields coloured by data that are drawn as lattice tiles: their values per grid sample
// (gpu::geometry::SceneGeometry::sample_values; no data as the most negative f32).
// (f32 bits, 8192 words to a row: gpu::geometry::SHADING_ROW.)
@group(0) @binding(6) var sample_values: texture_2d<u32>;

// Word `k` of `sample_values`.
fn sample_value(k: u32) -> f32 {
    return bitcast<f32>(textureLoad(sample_values, vec2<u32>(k % 8192u, k / 8192u), 0).x);
}

// The colouring scalar of vertex `vpos` of `tile`: the vertex's own `value`, or for a lattice tile
// with values the value of its sample (tile_position's column and row).
fn tile_value(vpos: vec3<f32>, tile: u32, value: f32) -> f32 {
    let v0 = bitcast<u32>(tile_grid_at(tile, 2u).x);
    if (v0 == 0xffffffffu) {
        return value;
    }
    return sample_value(v0 + u32(vpos.y) * bitcast<u32>(tile_grid_at(tile, 1u).w) + u32(vpos.x));
}

// The four fine samples of a height field with a normal map about render-space point `w`, each
// (dz/dx, dz/dy, z): a (c), b (c + x), e (c + y), h (c + x + y); q0 the point's grid coordinates,
// c the cell (clamped to the grid) and f the fraction of the clamped point within it.
struct SurfaceCell {
    q0: vec2<f32>,
    c: vec2<f32>,
    f: vec2<f32>,
    a: vec3<f32>,
    b: vec3<f32>,
    e: vec3<f32>,
    h: vec3<f32>,
}

fn surface_cell(o: Object, w: vec3<f32>) -> SurfaceCell {
    let d = w.xy - o.offset.xy - o.grid.xy;
    let n = o.grid_rows.zw;
    let q0 = vec2<f32>(dot(o.grid.zw, d), dot(o.grid_rows.xy, d));
    let q = clamp(q0, vec2<f32>(0.0), n - 1.0);
    let c = min(floor(q), n - 2.0);
    let nx = u32(n.x);
    let k = o.normal_map.x - 1u + u32(c.y) * nx + u32(c.x);
    return SurfaceCell(q0, c, q - c, gradient_height(k), gradient_height(k + 1u), gradient_height(k + nx),
                       gradient_height(k + nx + 1u));
}

// Sample `k` of a height field's normal map: (dz/dx, dz/dy, z).
fn gradient_height(k: u32) -> vec3<f32> {
    let s = surface_sample(k);
    return vec3<f32>(unpack2x16float(s.x), bitcast<f32>(s.y));
}

// The fine surface under render-space point `w` of a height field with a normal map:
// (dz/dx, dz/dy, z) interpolated bilinearly at the point's (x, y), so that every level of detail
// of a tile shades and colours by z as the fine surface does.
fn fine_surface(o: Object, w: vec3<f32>) -> vec3<f32> {
    return cell_surface(surface_cell(o, w));
}

// The bilinear interpolation of a cell's samples at its fraction f.
fn cell_surface(sc: SurfaceCell) -> vec3<f32> {
    return mix(mix(sc.a, sc.b, sc.f.x), mix(sc.e, sc.h, sc.f.x), sc.f.y);
}

// The shading normal and colouring scalar of a height field from its fine surface `fs` there
// (`fine_surface`), with the vertex scalar `s` (replaced when colouring by z).
fn surface_shading(o: Object, fs: vec3<f32>, s: f32) -> vec4<f32> {
    return vec4<f32>(normalize(vec3<f32>(-fs.xy * g.z_scale, 1.0)), select(s, fs.z, o.cmap.z > 1.5));
}

// A structured grid mesh's fine normal at grid coordinates `uv` (column, row), as its fine level
// interpolates its vertex normals: the cell's triangle (a, b, d) where the fraction along the
// columns is at least the one along the rows, else (a, d, c) (lod::structured_grid), so that
// every level of detail shades as level 0 does.
fn grid_mesh_normal(o: Object, uv: vec2<f32>) -> vec3<f32> {
    let n = o.grid_rows.zw;
    let q = clamp(uv, vec2<f32>(0.0), n - 1.0);
    let c = min(floor(q), n - 2.0);
    let f = q - c;
    let nx = u32(n.x);
    let k = o.normal_map.x - 1u + u32(c.y) * nx + u32(c.x);
    let a = vertex_normal(surface_sample(k).x);
    let d = vertex_normal(surface_sample(k + nx + 1u).x);
    var v: vec3<f32>;
    if (f.x >= f.y) {
        v = (1.0 - f.x) * a + (f.x - f.y) * vertex_normal(surface_sample(k + 1u).x) + f.y * d;
    } else {
        v = (1.0 - f.y) * a + (f.y - f.x) * vertex_normal(surface_sample(k + nx).x) + f.x * d;
    }
    return v;
}

// The shading normal and colouring scalar at render-space point `w`: from the fine surface for a
// height field with a normal map (the scalar replaced when colouring by z); from the fine grid's
// normals at the interpolated grid coordinates for a grid mesh (normal_map.y = 2; they travel in
// `vn.xy`); the interpolated vertex normal `vn` for a mesh with smooth normals (normal_map.y =
// 1); else the facet's normal from screen-space derivatives; with the vertex scalar `s`.
//
// Grid meshes are drawn by their own entry points (fs_grid, fs_grid_gl: `shading_grid`): on a CPU
// rasteriser the grid lookup costs every fragment of the pass whether taken or not (13 % of a
// reservoir grid's frame), so fs_main does without it and shades a grid mesh by its facets.
fn shading(o: Object, w: vec3<f32>, facet: vec3<f32>, vn: vec3<f32>, s: f32) -> vec4<f32> {
    if (o.normal_map.x == 0u || o.normal_map.y == 2u) {
        return mesh_shading(o, facet, vn, s);
    }
    return field_shading(o, w, s);
}

// `shading` for an object without a height field's normal map.
fn mesh_shading(o: Object, facet: vec3<f32>, vn: vec3<f32>, s: f32) -> vec4<f32> {
    if (o.normal_map.y == 1u && dot(vn, vn) > 1e-12) {
        return vec4<f32>(normalize(vn), s);
    }
    if (dot(facet, facet) > 0.0) {
        return vec4<f32>(normalize(facet), s);
    }
    return vec4<f32>(0.0, 0.0, 1.0, s);
}

// `shading` for a height field with a normal map: from its fine surface alone.
fn field_shading(o: Object, w: vec3<f32>, s: f32) -> vec4<f32> {
    return surface_shading(o, fine_surface(o, w), s);
}

// `shading` for a grid mesh: the fine grid's normal at the interpolated grid coordinates.
// (A grid mesh has no height field's normal map: `shading` would take its mesh branch.)
fn shading_grid(o: Object, facet: vec3<f32>, vn: vec3<f32>, s: f32) -> vec4<f32> {
    let gn = grid_mesh_normal(o, vn.xy);
    if (o.normal_map.y == 2u && dot(gn, gn) > 1e-12) {
        return vec4<f32>(normalize(gn), s);
    }
    return mesh_shading(o, facet, vn, s);
}

struct VOutDraw {
    @builtin(position) @invariant clip: vec4<f32>,
    // xyz: the render-space position; w: the colouring scalar, the vertex's value (mode 1) or its
    // object-relative z (mode 2). One varying for both: a CPU rasteriser stores and sets up each
    // varying of each binned triangle as four channels (lavapipe: 4-5 % of a frame).
    @location(0) world_s: vec4<f32>,
    @location(1) @interpolate(flat) tile: u32,
    // The vertex's smooth normal, exaggerated (0 where it has none); for a grid mesh its grid
    // coordinates (column, row, 0) instead (one varying for both, as above).
    @location(2) n: vec3<f32>,
}

// A packed smooth normal (lod::normals: octahedral, two snorm16; 0 = none) in render space,
// where z is exaggerated by z_scale (normals scale by its inverse).
fn vertex_normal(p: u32) -> vec3<f32> {
    if (p == 0u) {
        return vec3<f32>(0.0);
    }
    let n = octahedral(p);
    return normalize(vec3<f32>(n.xy, n.z / g.z_scale));
}

// A packed smooth normal's octahedral decoding (not normalised).
fn octahedral(p: u32) -> vec3<f32> {
    let e = unpack2x16snorm(p);
    var n = vec3<f32>(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) {
        n = vec3<f32>((1.0 - abs(n.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), n.xy >= vec2<f32>(0.0)), n.z);
    }
    return n;
}

// The normal a vertex carries to the fragment (`normal_slot`), where a well tube's ring is not
// exaggerated (ring height `rz` not 0 and z_scale > 1, common.wgsl `ring_lift`): its radial
// normal as is. (A ring vertex's radial normal has a vertical part exactly where its ring height
// is not 0.)
fn drawn_normal(o: Object, nrm: u32, rz: f32) -> vec3<f32> {
    if (rz != 0.0 && g.z_scale > 1.0 && nrm != 0u) {
        return normalize(octahedral(nrm));
    }
    return normal_slot(o, nrm);
}

@vertex
fn vs_draw(@location(0) vpos: vec3<f32>, @location(1) vvalue: f32, @location(2) nrm: u32,
           @location(3) rz: f32, @builtin(instance_index) tile: u32) -> VOutDraw {
    let o = object_at(tile);
    let pos = tile_position(vpos, tile);
    let value = tile_value(vpos, tile, vvalue);
    let p = (pos - ring_lift(rz) + o.offset.xyz) * vec3<f32>(1.0, 1.0, g.z_scale);
    var out: VOutDraw;
    out.clip = priority_clip(g.view_proj * vec4<f32>(p, 1.0), o);
    out.world_s = vec4<f32>(p, select(value, pos.z, o.cmap.z > 1.5));
    out.tile = tile;
    out.n = drawn_normal(o, nrm, rz);
    return out;
}

// What a vertex's normal slot carries (`gpu::geometry::normal_slot`): a packed smooth normal, a
// grid mesh's grid coordinates (normal_map.y = 2) or a reservoir grid's cell coordinates
// (normal_map.y = 3, `grid::cells`: doubled, block-relative, i | j << 8 | k << 16).
fn normal_slot(o: Object, nrm: u32) -> vec3<f32> {
    if (o.normal_map.y == 3u) {
        return vec3<f32>(f32(nrm & 0xffu), f32((nrm >> 8u) & 0xffu), f32(nrm >> 16u));
    }
    return select(vertex_normal(nrm), vec3<f32>(grid_coords(nrm), 0.0), o.normal_map.y == 2u);
}

// The colouring scalar of a fragment of a reservoir grid coloured per cell: the value of the cell
// its interpolated cell coordinates `c` fall in, from the tile's table in `sample_values`
// (`gpu::cell_values`: columns bw, bh and first word in its grid, `tile_grid_at`); the vertex
// scalar `s` where the grid is coloured otherwise, the face is flat or the table holds no value
// for that cell (f32::MAX).
fn cell_scalar(o: Object, tile: u32, c: vec3<f32>, s: f32) -> f32 {
    // (k = 0xffff: a face coloured flat, grid::cells::FLAT.)
    if (o.normal_map.y != 3u || c.z > 65534.5) {
        return s;
    }
    let b = tile_grid_at(tile, 1u);
    let dims = vec2<u32>(bitcast<u32>(b.x), bitcast<u32>(b.y));
    let first = bitcast<u32>(tile_grid_at(tile, 2u).y);
    let q = max(floor(c * 0.5), vec3<f32>(0.0));
    let i = min(u32(q.x), dims.x - 1u);
    let j = min(u32(q.y), dims.y - 1u);
    let w = sample_value(first + (u32(q.z) * dims.y + j) * dims.x + i);
    return select(w, s, w > 3e38);
}

// The log value of a well's fragment at its interpolated station `s` (counted from the tile's
// first station, lod::tube): linear between the stations about it in the tile's table
// (`gpu::cell_values`: its stations as columns, first word in its grid, `tile_grid_at`), as level 0's vertex
// values interpolate; no data (the most negative f32) spreads as there.
fn log_scalar(tile: u32, s: f32) -> f32 {
    let n = bitcast<u32>(tile_grid_at(tile, 1u).x);
    let first = bitcast<u32>(tile_grid_at(tile, 2u).y);
    let k = min(u32(max(s, 0.0)), n - 1u);
    let a = sample_value(first + k);
    let b = sample_value(first + min(k + 1u, n - 1u));
    return a + clamp(s - f32(k), 0.0, 1.0) * (b - a);
}

// The colouring scalar of a fragment of an object coloured from tables (`gpu::cell_values`): a
// well's log (log_scalar) or a reservoir grid's cell value (cell_scalar).
fn table_scalar(o: Object, tile: u32, c: vec3<f32>, s: f32) -> f32 {
    if (o.normal_map.w == 1u) {
        return log_scalar(tile, s);
    }
    return cell_scalar(o, tile, c, s);
}

// A grid mesh's vertex's packed grid coordinates (lod::TileMesh::grid_uv: column | row << 16).
fn grid_coords(p: u32) -> vec2<f32> {
    return vec2<f32>(f32(p & 0xffffu), f32(p >> 16u));
}

// The object's colour at scalar s: flat, or matplotlib's mapping of a 256-row colour map
// (row floor(256 t), t = (s - lo) / (hi - lo) clamped to [0, 1], the last row at t = 1); scalars
// below -1e31 are no data (geometry.rs NO_DATA, -3.4e38, or an interpolation with it: the other
// scalars come clamped to ±1e30) and get the NaN colour.
fn base_color(o: Object, s: f32) -> vec3<f32> {
    if (o.cmap.z < 0.5) {
        return o.color.rgb;
    }
    let table = u32(o.cmap.w);
    if (s < -1e31) {
        return lut_row(table, 256u);
    }
    let t = clamp((s - o.cmap.x) * o.cmap.y, 0.0, 1.0);
    return lut_row(table, min(u32(t * 256.0), 255u));
}

// The lit colour of object `o` at a fragment with shading normal and colouring scalar `ns`
// (`shading`): two-sided Lambert, a head light (so nothing facing the viewer is dark) plus a fixed
// sun from the north-west at 50° elevation (so gentle undulations of a horizon read as relief).
// Translucent objects (volume lenses, drawn blended) are unlit, with the object's opacity.
fn lit_color(o: Object, ns: vec4<f32>) -> vec4<f32> {
    let n = ns.xyz;
    let c = base_color(o, ns.w);
    let sun = vec3<f32>(-0.45, 0.45, 0.77);
    let shade = 0.2 + 0.45 * abs(dot(n, g.light_dir.xyz)) + 0.35 * abs(dot(n, sun));
    return vec4<f32>(c * select(shade, 1.0, o.color.a < 1.0), o.color.a);
}

struct FOut {
    @location(0) color: vec4<f32>,
    // Tile index + 1 of the visible surface (0 = nothing).
    @location(1) id: u32,
}

@fragment
fn fs_main(v: VOutDraw) -> FOut {
    let o = object_at(v.tile);
    let ns = shading(o, v.world_s.xyz, cross(dpdx(v.world_s.xyz), dpdy(v.world_s.xyz)), v.n, v.world_s.w);
    return FOut(lit_color(o, ns), v.tile + 1u);
}

// fs_main for the opaque tiles of objects without a height field's normal map (meshes, wells,
// slices, reservoir grids, height fields whose map did not fit): their tiles never take the
// field branch, which a CPU rasteriser would run for every fragment (gpu::geometry::DrawRun).
@fragment
fn fs_mesh(v: VOutDraw) -> FOut {
    let o = object_at(v.tile);
    return FOut(lit_color(o, mesh_shading(o, cross(dpdx(v.world_s.xyz), dpdy(v.world_s.xyz)), v.n, v.world_s.w)), v.tile + 1u);
}

// fs_mesh for the tiles of objects coloured from tables: reservoir grids per cell, wells by their
// logs (gpu::geometry::DrawRun::cells).
@fragment
fn fs_cells(v: VOutDraw) -> FOut {
    let o = object_at(v.tile);
    let s = table_scalar(o, v.tile, v.n, v.world_s.w);
    return FOut(lit_color(o, mesh_shading(o, cross(dpdx(v.world_s.xyz), dpdy(v.world_s.xyz)), v.n, s)), v.tile + 1u);
}

// fs_main for the tiles of grid meshes (gpu::geometry::SceneGeometry::draw_runs).
@fragment
fn fs_grid(v: VOutDraw) -> FOut {
    let o = object_at(v.tile);
    let ns = shading_grid(o, cross(dpdx(v.world_s.xyz), dpdy(v.world_s.xyz)), v.n, v.world_s.w);
    return FOut(lit_color(o, ns), v.tile + 1u);
}

// The tiles of height fields with a normal map (gpu::geometry::DrawRun::field): shaded and
// coloured from the fine surface alone (field_shading), so they carry neither a smooth normal nor
// screen-space derivatives. A CPU rasteriser stores and interpolates every varying of every binned
// triangle and runs every branch of a shader for every lane: fs_main would pay for the mesh
// paths on every horizon fragment.
struct VOutField {
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) world_s: vec4<f32>,
    @location(1) @interpolate(flat) tile: u32,
}

@vertex
fn vs_field(@location(0) vpos: vec3<f32>, @location(1) vvalue: f32, @builtin(instance_index) tile: u32) -> VOutField {
    return field_vertex(vpos, vvalue, tile, object_at(tile));
}

// vs_field's output for vertex `vpos` (its scalar `vvalue`) of `tile` of object `o`.
fn field_vertex(vpos: vec3<f32>, vvalue: f32, tile: u32, o: Object) -> VOutField {
    let pos = tile_position(vpos, tile);
    let value = tile_value(vpos, tile, vvalue);
    let p = (pos + o.offset.xyz) * vec3<f32>(1.0, 1.0, g.z_scale);
    return VOutField(priority_clip(g.view_proj * vec4<f32>(p, 1.0), o), vec4<f32>(p, select(value, pos.z, o.cmap.z > 1.5)), tile);
}

@fragment
fn fs_field(v: VOutField) -> FOut {
    let o = object_at(v.tile);
    return FOut(lit_color(o, field_shading(o, v.world_s.xyz, v.world_s.w)), v.tile + 1u);
}

// The depth of the fine surface of height field `o` (with a normal map) on the pixel ray through
// render-space point `w`, a fragment of one of its coarser levels: the fine level's two triangles
// per cell (split from sample (i, j) to (i + 1, j + 1), lod::tile_heightfield) with the heights
// of the normal map, the ray meeting the plane of the fine triangle under `w` (cell `c`, heights
// `z` = (z00, z10, z01, z11), as `fine_surface` loaded them), then of the one under that meeting
// point. A coarser level lies within its error of the fine surface, but two surfaces that nearly
// coincide (a grid's top built from a horizon) cross each other along lines that any vertical
// change moves by far more than that error on screen; with the fine depth they hide each other
// as at level 0, and only the level's outline moves (gpu::geometry::DrawRun::fine_depth). The
// meeting point is kept only where it lies on the fine triangle whose plane gave it and inside
// `tile`'s samples (`tile_grid_at`, gpu::geometry::plan), in a tile with holes on the fine triangle
// under `w` itself, so that every depth written is a point of the tile's own fine surface or,
// else, of its drawn level (`w`: a ray grazing the surface, an outline the fine surface does not
// reach): both lie where the culling tests (cull::phases, cull::hidden) take the tile to lie, the
// slab grown by a lattice level's error or the tile's box.
fn fine_depth(o: Object, tile: u32, w: vec3<f32>, q0: vec2<f32>, c0: vec2<f32>, z0: vec4<f32>) -> f32 {
    let r = select(g.eye.xyz, w - g.eye.xyz, g.eye.w > 0.5);
    let zs = g.z_scale;
    let qr = vec2<f32>(dot(o.grid.zw, r.xy), dot(o.grid_rows.xy, r.xy));
    // The plane of the fine triangle of cell c with heights z over (column, row) meets the ray
    // w + s r where w.z + s r.z = zs (offset.z + z00 + a.(q0 + s qr - c)).
    var f = clamp(q0, vec2<f32>(0.0), o.grid_rows.zw - 1.0) - c0;
    var a = select(vec2<f32>(z0.w - z0.z, z0.z - z0.x), vec2<f32>(z0.y - z0.x, z0.w - z0.y), f.x >= f.y);
    var gap = zs * (o.offset.z + z0.x + dot(a, q0 - c0)) - w.z;
    var den = r.z - zs * dot(a, qr);
    // (Bounded, so that no product below is infinite times zero.)
    var t = clamp(select(0.0, gap / den, abs(den) > 1e-30), -1e9, 1e9);
    // Once more with the triangle under that meeting point.
    let n = o.grid_rows.zw;
    let q = clamp(q0 + t * qr, vec2<f32>(0.0), n - 1.0);
    let c = min(floor(q), n - 2.0);
    f = q - c;
    let nx = u32(n.x);
    let k = o.normal_map.x - 1u + u32(c.y) * nx + u32(c.x);
    let z00 = bitcast<f32>(surface_sample(k).y);
    let z11 = bitcast<f32>(surface_sample(k + nx + 1u).y);
    let zo = bitcast<f32>(surface_sample(select(k + nx, k + 1u, f.x >= f.y)).y);
    a = select(vec2<f32>(z11 - zo, zo - z00), vec2<f32>(zo - z00, z11 - zo), f.x >= f.y);
    gap = zs * (o.offset.z + z00 + dot(a, q0 - c)) - w.z;
    den = r.z - zs * dot(a, qr);
    t = clamp(select(0.0, gap / den, abs(den) > 1e-30), -1e9, 1e9);
    // On that triangle (up to round-off) and inside the tile, else the level's own point; in a
    // tile with holes (top bit of its columns' word) on the triangle under `w` itself, as the
    // cells under a hole hold no fine triangle, only the normal map's filled heights.
    let fx = q0 + t * qr - c;
    let e = 1e-3;
    let side = select(fx.y - fx.x, fx.x - fx.y, f.x >= f.y);
    var on = all(fx >= vec2<f32>(-e)) && all(fx <= vec2<f32>(1.0 + e)) && side >= -e;
    let dom = vec2<u32>(bitcast<u32>(tile_grid_at(tile, 2u).z), bitcast<u32>(tile_grid_at(tile, 2u).w));
    let lo = vec2<f32>(vec2<u32>(dom.x & 0xffffu, dom.y & 0xffffu));
    let hi = vec2<f32>(vec2<u32>((dom.x >> 16u) & 0x7fffu, dom.y >> 16u));
    let qx = c + fx;
    on = on && dom.x != 0xffffffffu && dom.y != 0xffffffffu && all(qx >= lo - e) && all(qx <= hi + e);
    let f0 = clamp(q0, vec2<f32>(0.0), n - 1.0) - c0;
    let same = all(c == c0) && ((f0.x >= f0.y) == (f.x >= f.y));
    on = on && (dom.x < 0x80000000u || same);
    let clip = priority_clip(g.view_proj * vec4<f32>(w + select(0.0, t, on) * r, 1.0), o);
    return clip.z / clip.w;
}

// `field_shading` and `fine_depth` at render-space point `w` of a coarser level, from one load of
// the four samples around it.
struct FieldFine {
    ns: vec4<f32>,
    depth: f32,
}

fn field_fine(o: Object, tile: u32, w: vec3<f32>, s: f32) -> FieldFine {
    let sc = surface_cell(o, w);
    let fs = cell_surface(sc);
    let depth = fine_depth(o, tile, w, sc.q0, sc.c, vec4<f32>(sc.a.z, sc.b.z, sc.e.z, sc.h.z));
    return FieldFine(surface_shading(o, fs, s), depth);
}

struct FOutDepth {
    @location(0) color: vec4<f32>,
    @location(1) id: u32,
    @builtin(frag_depth) depth: f32,
}

// VOutField with the tile's object carried flat, for fs_field_fine: its fragments read nearly all
// of the object (the grid, the colour map, the offset), and a CPU rasteriser reads storage lane by
// lane for every fragment, where a flat varying costs once a vertex. Coarser levels have few
// vertices and many fragments each (Reek, 8 views, lavapipe: the lit pass 7 % faster, 0.86-0.99,
// the same images); level 0 (fs_field) has many vertices, and keeps its reads.
struct VOutFieldFine {
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) world_s: vec4<f32>,
    @location(1) @interpolate(flat) tile: u32,
    @location(2) @interpolate(flat) offset: vec4<f32>,
    @location(3) @interpolate(flat) color: vec4<f32>,
    @location(4) @interpolate(flat) cmap: vec4<f32>,
    @location(5) @interpolate(flat) grid: vec4<f32>,
    @location(6) @interpolate(flat) grid_rows: vec4<f32>,
    @location(7) @interpolate(flat) normal_map: vec4<u32>,
}

@vertex
fn vs_field_fine(@location(0) vpos: vec3<f32>, @location(1) vvalue: f32, @builtin(instance_index) tile: u32) -> VOutFieldFine {
    let o = object_at(tile);
    let v = field_vertex(vpos, vvalue, tile, o);
    return VOutFieldFine(v.clip, v.world_s, tile, o.offset, o.color, o.cmap, o.grid, o.grid_rows, o.normal_map);
}

// fs_field for the tiles of height fields drawn at a coarser level than their fine one: the fine
// surface's depth written (`fine_depth`).
@fragment
fn fs_field_fine(v: VOutFieldFine) -> FOutDepth {
    let o = Object(v.offset, v.color, v.cmap, v.grid, v.grid_rows, v.normal_map);
    let ff = field_fine(o, v.tile, v.world_s.xyz, v.world_s.w);
    return FOutDepth(lit_color(o, ff.ns), v.tile + 1u, ff.depth);
}

// GL: vs_draw's transform with clip z and w carried to the fragment (see VOutGl in common.wgsl).
struct VOutDrawGl {
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) world_s: vec4<f32>,
    @location(1) @interpolate(flat) tile: u32,
    @location(2) zw: vec2<f32>,
    @location(3) n: vec3<f32>,
}

@vertex
fn vs_draw_gl(@location(0) vpos: vec3<f32>, @location(1) vvalue: f32, @location(2) nrm: u32,
              @location(3) rz: f32, @builtin(instance_index) tile: u32) -> VOutDrawGl {
    let o = object_at(tile);
    let pos = tile_position(vpos, tile);
    let value = tile_value(vpos, tile, vvalue);
    let p = (pos - ring_lift(rz) + o.offset.xyz) * vec3<f32>(1.0, 1.0, g.z_scale);
    let clip = priority_clip(g.view_proj * vec4<f32>(p, 1.0), o);
    let n = drawn_normal(o, nrm, rz);
    return VOutDrawGl(clip, vec4<f32>(p, select(value, pos.z, o.cmap.z > 1.5)), tile, clip.zw, n);
}

struct FOutGl {
    @location(0) color: vec4<f32>,
    @location(1) id: u32,
    @builtin(frag_depth) depth: f32,
}

// GL: the same shading as fs_main (kept apart so that fs_main's code is what it always was), with
// frag_depth written (see VOutGl in common.wgsl).
@fragment
fn fs_main_gl(v: VOutDrawGl) -> FOutGl {
    let o = object_at(v.tile);
    let ns = shading(o, v.world_s.xyz, cross(dpdx(v.world_s.xyz), dpdy(v.world_s.xyz)), v.n, v.world_s.w);
    return FOutGl(lit_color(o, ns), v.tile + 1u, v.zw.x / v.zw.y);
}

// fs_mesh with frag_depth written.
@fragment
fn fs_mesh_gl(v: VOutDrawGl) -> FOutGl {
    let o = object_at(v.tile);
    let ns = mesh_shading(o, cross(dpdx(v.world_s.xyz), dpdy(v.world_s.xyz)), v.n, v.world_s.w);
    return FOutGl(lit_color(o, ns), v.tile + 1u, v.zw.x / v.zw.y);
}

// fs_cells with frag_depth written.
@fragment
fn fs_cells_gl(v: VOutDrawGl) -> FOutGl {
    let o = object_at(v.tile);
    let s = table_scalar(o, v.tile, v.n, v.world_s.w);
    let ns = mesh_shading(o, cross(dpdx(v.world_s.xyz), dpdy(v.world_s.xyz)), v.n, s);
    return FOutGl(lit_color(o, ns), v.tile + 1u, v.zw.x / v.zw.y);
}

// fs_main_gl for the tiles of grid meshes.
@fragment
fn fs_grid_gl(v: VOutDrawGl) -> FOutGl {
    let o = object_at(v.tile);
    let ns = shading_grid(o, cross(dpdx(v.world_s.xyz), dpdy(v.world_s.xyz)), v.n, v.world_s.w);
    return FOutGl(lit_color(o, ns), v.tile + 1u, v.zw.x / v.zw.y);
}

// GL: vs_field / fs_field with frag_depth written (see VOutGl in common.wgsl).
struct VOutFieldGl {
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) world_s: vec4<f32>,
    @location(1) @interpolate(flat) tile: u32,
    @location(2) zw: vec2<f32>,
}

@vertex
fn vs_field_gl(@location(0) vpos: vec3<f32>, @location(1) vvalue: f32,
               @builtin(instance_index) tile: u32) -> VOutFieldGl {
    let o = object_at(tile);
    let pos = tile_position(vpos, tile);
    let value = tile_value(vpos, tile, vvalue);
    let p = (pos + o.offset.xyz) * vec3<f32>(1.0, 1.0, g.z_scale);
    let clip = priority_clip(g.view_proj * vec4<f32>(p, 1.0), o);
    return VOutFieldGl(clip, vec4<f32>(p, select(value, pos.z, o.cmap.z > 1.5)), tile, clip.zw);
}

@fragment
fn fs_field_gl(v: VOutFieldGl) -> FOutGl {
    let o = object_at(v.tile);
    return FOutGl(lit_color(o, field_shading(o, v.world_s.xyz, v.world_s.w)), v.tile + 1u, v.zw.x / v.zw.y);
}

// GL: fs_field_fine as it is (it writes frag_depth already).
@fragment
fn fs_field_fine_gl(v: VOutFieldGl) -> FOutGl {
    let o = object_at(v.tile);
    let ff = field_fine(o, v.tile, v.world_s.xyz, v.world_s.w);
    return FOutGl(lit_color(o, ff.ns), v.tile + 1u, ff.depth);
}
