// Implicit occluders (Pesco et al.): the occlusion map and the march cells seen in front of it,
// marched per pixel through the occluder classes, and the lit isosurface.
// Depth is reverse-Z everywhere (1 = near, 0 = far): "nearer" means a larger depth value.

struct Globals {
    view_proj: mat4x4<f32>,
    // Direction towards the light (render space), w unused.
    light_dir: vec4<f32>,
    color: vec4<f32>,
}

@group(0) @binding(0) var<uniform> g: Globals;

// ---- The occlusion map and the node test in one compute pass, one invocation per pixel: the
// pixel's ray walks the grid of cells at the march depth (the finer of the occluder and cull depths)
// near to far (3-D DDA) and stops in the first occluder node of one class (Below / Above) met after
// an occluder node of the other class with no NaN node in between; the map is the depth of that
// node's entry point, pushed farther by `lo.w` (render units), 0 (= far, nothing proven) where no
// such pair exists. Every march cell that may hold surface (passable or NaN) the walk enters up to
// and including that cell is seen: its bit in `cells_seen` is set; a cell the ray passes within
// `hi.w` (grid units) of is marked too, so rounding never skips one. A cull node is visible when
// one of its cells is seen (counted on the CPU).
// Classes: 2 bits per occluder node, 16 per word: 0 = may hold surface (passable), 1 = Below,
// 2 = Above, 3 = has a NaN sample (outside the domain: resets the walk).
struct MapParams {
    inv_view_proj: mat4x4<f32>,
    // xyz: the volume's box (render space); lo.w: the map's margin (render units); hi.w: the
    // margin for marking a neighbouring cell (fraction of a march cell).
    lo: vec4<f32>,
    hi: vec4<f32>,
    // xyz: a march cell's size (render space); the last one per axis may end earlier, at `hi`.
    node: vec4<f32>,
    // xyz: march cells per axis; w: image width.
    dims: vec4<u32>,
    // x: image height; y: march depth - occluder depth; z: unused; w: 1 = mark the march cells
    // seen in `cells_seen` (1 bit each).
    size: vec4<u32>,
    // xyz: occluder nodes per axis; w: unused.
    occ_dims: vec4<u32>,
    // Unused (the cull nodes are counted on the CPU).
    cull_dims: vec4<u32>,
    // Skip bricks (iso/bricks.rs): x, y: log2 of the fine and the coarse bricks' size in occluder
    // nodes (x = 0: no skipping); z, w: the first word of their 2-bit classes in `classes`.
    bricks: vec4<u32>,
}

@group(1) @binding(0) var<uniform> mp: MapParams;
@group(1) @binding(1) var<storage, read> classes: array<u32>;
@group(1) @binding(2) var<storage, read_write> map_out: array<f32>;
@group(1) @binding(3) var<storage, read_write> cells_seen: array<atomic<u32>>;

fn mark_cell(c: vec3<i32>) {
    if (mp.size.w == 1u) {
        let u = vec3<u32>(c);
        let i = (u.z * mp.dims.y + u.y) * mp.dims.x + u.x;
        let bit = 1u << (i & 31u);
        // Most cells are seen by many rays: a load first spares the atomic read-modify-write.
        if ((atomicLoad(&cells_seen[i >> 5u]) & bit) == 0u) {
            atomicOr(&cells_seen[i >> 5u], bit);
        }
    }
}

fn node_class(c: vec3<i32>) -> u32 {
    let u = vec3<u32>(c) >> vec3<u32>(mp.size.y);
    let i = (u.z * mp.occ_dims.y + u.y) * mp.occ_dims.x + u.x;
    return (classes[i >> 4u] >> ((i & 15u) * 2u)) & 3u;
}

// The class of the skip brick of `2^s` occluder nodes per axis that holds march cell `c`: 1 / 2
// when it and its one-node ring are all Below / Above, else 0.
fn brick_class(c: vec3<i32>, s: u32, off: u32) -> u32 {
    let u = vec3<u32>(c) >> vec3<u32>(mp.size.y + s);
    let bd = (mp.occ_dims.xyz + vec3<u32>((1u << s) - 1u)) >> vec3<u32>(s);
    let i = (u.z * bd.y + u.y) * bd.x + u.x;
    return (classes[off + (i >> 4u)] >> ((i & 15u) * 2u)) & 3u;
}

// Where the ray `o + t d` (`inv` = 1 / d) leaves cell `c` across each axis (the DDA's next
// crossings): a function of the cell alone, so a brick jump lands in the state the cell-by-cell
// walk would reach, bit for bit.
fn exits(c: vec3<i32>, o: vec3<f32>, inv: vec3<f32>, ahead: vec3<f32>) -> vec3<f32> {
    return (mp.lo.xyz + (vec3<f32>(c) + ahead) * mp.node.xyz - o) * inv;
}

fn unproject(ndc: vec3<f32>) -> vec3<f32> {
    let p = mp.inv_view_proj * vec4<f32>(ndc, 1.0);
    return p.xyz / p.w;
}

// At the entry point `g` (march-cell units) of cell `c`: every cell that touches `g` within `hi.w`
// along each axis (across a face, an edge or a corner) is marked when it may hold surface; the ray
// may have skipped it by rounding. The axis just crossed (`crossed`) has its other side marked
// already.
fn mark_near(g: vec3<f32>, c: vec3<i32>, dims: vec3<i32>, crossed: i32) {
    var off = vec3<i32>(0);
    var any_near = false;
    for (var a = 0; a < 3; a++) {
        let r = floor(g[a] + 0.5);
        if (a != crossed && abs(g[a] - r) < mp.hi.w) {
            off[a] = select(1, -1, c[a] == i32(r));
            any_near = true;
        }
    }
    if (!any_near) {
        return;
    }
    for (var m = 1; m < 8; m++) {
        let pick = vec3<bool>((m & 1) != 0, (m & 2) != 0, (m & 4) != 0);
        if (any(pick & (off == vec3<i32>(0)))) {
            continue;
        }
        let n = c + select(vec3<i32>(0), off, pick);
        if (all(n >= vec3<i32>(0)) && all(n < dims)) {
            let kn = node_class(n);
            if (kn == 0u || kn == 3u) {
                mark_cell(n);
            }
        }
    }
}

@compute @workgroup_size(8, 8)
fn cs_map(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = mp.dims.w;
    let h = mp.size.x;
    if (gid.x >= w || gid.y >= h) {
        return;
    }
    let ndc = vec2<f32>((f32(gid.x) + 0.5) / f32(w) * 2.0 - 1.0, 1.0 - (f32(gid.y) + 0.5) / f32(h) * 2.0);
    // From the near plane along the pixel's ray (t = 0 at the near plane).
    let o = unproject(vec3<f32>(ndc, 1.0));
    var d = unproject(vec3<f32>(ndc, 0.5)) - o;
    d = select(d, vec3<f32>(1e-30), abs(d) < vec3<f32>(1e-30));
    let inv = 1.0 / d;
    // The walk covers the box widened by the marking margin: a ray that passes just outside it
    // still marks the border cells (the rasteriser's snapping may cover its pixel with their
    // triangles). Proofs use only cells the ray meets inside the box itself, `[in0, in1]`.
    let margin = mp.hi.w * mp.node.xyz;
    let ta = (mp.lo.xyz - o) * inv;
    let tb = (mp.hi.xyz - o) * inv;
    let in0 = max(max(min(ta.x, tb.x), min(ta.y, tb.y)), max(min(ta.z, tb.z), 0.0));
    let in1 = min(min(max(ta.x, tb.x), max(ta.y, tb.y)), max(ta.z, tb.z));
    let tmin = min(ta, tb) - abs(margin * inv);
    let tmax = max(ta, tb) + abs(margin * inv);
    let t0 = max(max(tmin.x, tmin.y), max(tmin.z, 0.0));
    let t1 = min(min(tmax.x, tmax.y), tmax.z);
    var result = 0.0;
    if (t0 < t1) {
        let dims = vec3<i32>(mp.dims.xyz);
        let p = o + d * t0;
        var c = vec3<i32>(clamp(floor((p - mp.lo.xyz) / mp.node.xyz), vec3<f32>(0.0), vec3<f32>(dims - 1)));
        let stp = select(vec3<i32>(-1), vec3<i32>(1), d > vec3<f32>(0.0));
        let ahead = select(vec3<f32>(0.0), vec3<f32>(1.0), d > vec3<f32>(0.0));
        var tnext = exits(c, o, inv, ahead);
        var last = 0u;
        var t_enter = t0;
        var crossed = -1;
        loop {
            let k = node_class(c);
            // Below / Above cells (uniform, NaN-free) hold no triangle: the others need their bit.
            if (k == 0u || k == 3u) {
                mark_cell(c);
            }
            mark_near((o + d * t_enter - mp.lo.xyz) / mp.node.xyz, c, dims, crossed);
            let tm = min(min(tnext.x, tnext.y), tnext.z);
            // A NaN cell, or a cell met only in the margin outside the box, breaks every pair.
            if (k == 3u || tm <= in0 || t_enter >= in1) {
                last = 0u;
            } else if (k != 0u) {
                if (last != 0u && last != k) {
                    let q = o + d * (t_enter + mp.lo.w / length(d));
                    let clip = g.view_proj * vec4<f32>(q, 1.0);
                    result = clamp(clip.z / clip.w, 0.0, 1.0);
                    break;
                }
                last = k;
            }
            // Space skipping: in a brick of class `last` (it and its ring all of that class) the
            // walk would mark nothing and never stop, so it jumps to where it leaves the brick
            // (`last == k`: the cell counted; `k` is then Below or Above).
            // A coarse brick is skippable only if its fine bricks are.
            var s = 0u;
            if (mp.bricks.x != 0u && last == k && k != 0u && brick_class(c, mp.bricks.x, mp.bricks.z) != 0u) {
                s = mp.size.y + mp.bricks.x;
                if (brick_class(c, mp.bricks.y, mp.bricks.w) != 0u) {
                    s = mp.size.y + mp.bricks.y;
                }
            }
            if (s != 0u) {
                // The brick's last cell along the ray on each axis, and where the ray leaves it
                // (ties to the lower axis, as the steps below).
                let blo = (c >> vec3<u32>(s)) << vec3<u32>(s);
                let e = select(blo, min(blo + vec3<i32>((1 << s) - 1), dims - 1), stp > vec3<i32>(0));
                let x = exits(e, o, inv, ahead);
                var a = 0;
                if (x.y < x[a]) {
                    a = 1;
                }
                if (x.z < x[a]) {
                    a = 2;
                }
                let tx = x[a];
                if (tx >= t1) {
                    break;
                }
                // The other axes advance while their crossing comes first (a tie goes to the
                // lower axis).
                for (var b = 0; b < 3; b++) {
                    if (b == a) {
                        c[b] = e[b] + stp[b];
                        continue;
                    }
                    loop {
                        let tc = exits(c, o, inv, ahead)[b];
                        if (c[b] == e[b] || tc > tx || (b > a && tc == tx)) {
                            break;
                        }
                        c[b] += stp[b];
                    }
                }
                tnext = exits(c, o, inv, ahead);
                t_enter = tx;
                crossed = a;
                if (any(c < vec3<i32>(0)) || any(c >= dims)) {
                    break;
                }
                continue;
            }
            if (tm >= t1) {
                break;
            }
            t_enter = tm;
            // One axis at a time: a ray through an edge or corner visits the cells beside it too.
            if (tnext.x <= tm) {
                c.x += stp.x;
                crossed = 0;
            } else if (tnext.y <= tm) {
                c.y += stp.y;
                crossed = 1;
            } else {
                c.z += stp.z;
                crossed = 2;
            }
            tnext = exits(c, o, inv, ahead);
            if (any(c < vec3<i32>(0)) || any(c >= dims)) {
                break;
            }
        }
    }
    map_out[gid.y * w + gid.x] = result;
}

// The isosurface: positions relative to the volume centre (render space), smooth normals.
struct SurfOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
}

@vertex
fn vs_surf(@location(0) pos: vec3<f32>, @location(1) normal: vec3<f32>) -> SurfOut {
    var out: SurfOut;
    out.clip = g.view_proj * vec4<f32>(pos, 1.0);
    out.normal = normal;
    return out;
}

@fragment
fn fs_surf(v: SurfOut) -> @location(0) vec4<f32> {
    var n = vec3<f32>(0.0, 0.0, 1.0);
    if (dot(v.normal, v.normal) > 0.0) {
        n = normalize(v.normal);
    }
    // Two-sided Lambert with an ambient term.
    let shade = 0.3 + 0.7 * abs(dot(n, g.light_dir.xyz));
    return vec4<f32>(g.color.rgb * shade, 1.0);
}

// ---- The GL variant (`*_gl` entry points, chosen by IsoPasses::new on the GL backend): clip z and
// w go to the fragment, which uses z / w as its depth (compared by hand and written as frag_depth)
// instead of GL's own depth, which keeps only ~2^-24 absolute precision of reverse-Z depth (see
// gpu/shaders/common.wgsl). The bodies repeat those above rather than sharing helpers, so that the
// other backends' entry points compile exactly as before (a shared shading helper measurably
// slowed lavapipe's lit pass).

struct SurfOutGl {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) zw: vec2<f32>,
}

@vertex
fn vs_surf_gl(@location(0) pos: vec3<f32>, @location(1) normal: vec3<f32>) -> SurfOutGl {
    let clip = g.view_proj * vec4<f32>(pos, 1.0);
    return SurfOutGl(clip, normal, clip.zw);
}

struct SurfFragGl {
    @location(0) color: vec4<f32>,
    @builtin(frag_depth) depth: f32,
}

@fragment
fn fs_surf_gl(v: SurfOutGl) -> SurfFragGl {
    var n = vec3<f32>(0.0, 0.0, 1.0);
    if (dot(v.normal, v.normal) > 0.0) {
        n = normalize(v.normal);
    }
    let shade = 0.3 + 0.7 * abs(dot(n, g.light_dir.xyz));
    return SurfFragGl(vec4<f32>(g.color.rgb * shade, 1.0), v.zw.x / v.zw.y);
}
