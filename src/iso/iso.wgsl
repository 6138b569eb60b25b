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
// and including that cell is seen: its bit in `cells_seen` is set; where the ray enters a cell
// within `hi.w` (grid units) of a grid plane, a near event along that axis is set, and the CPU
// marks the cells across it (iso/seen.rs), so rounding never skips one. A cull node is visible
// when one of its cells is seen (counted on the CPU).
// Classes (`node_info`): 0 = may hold surface (passable), 1 = Below, 2 = Above, 3 = has a NaN
// sample (outside the domain: resets the walk).
struct MapParams {
    // The pixel's ray, affine in its NDC (x, y), built in f64 on the host: origin on the near
    // plane `ray_o + x ray_ox + y ray_oy`, direction `ray_d + x ray_dx + y ray_dy`.
    ray_o: vec4<f32>,
    ray_ox: vec4<f32>,
    ray_oy: vec4<f32>,
    ray_d: vec4<f32>,
    ray_dx: vec4<f32>,
    ray_dy: vec4<f32>,
    // xyz: the volume's box (render space); lo.w: the map's margin (render units); hi.w: the
    // margin for marking a neighbouring cell (fraction of a march cell).
    lo: vec4<f32>,
    hi: vec4<f32>,
    // xyz: a march cell's size (render space); the last one per axis may end earlier, at `hi`.
    node: vec4<f32>,
    // xyz: march cells per axis; w: image width.
    dims: vec4<u32>,
    // x: image height; y: march depth - occluder depth; z: 1 = the nodes carry their faces'
    // classes and are the march cells (single cells); w: 1 = mark the march cells
    // in `cells_seen` (4 bits each, `mark_cell`).
    size: vec4<u32>,
    // xyz: occluder nodes per axis; w: unused.
    occ_dims: vec4<u32>,
    // Unused (the cull nodes are counted on the CPU).
    cull_dims: vec4<u32>,
    // Skip bricks (iso/bricks.rs): x, y: log2 of the fine and the coarse bricks' size in occluder
    // nodes (x = 0: no skipping; the nodes' flags say which bricks are skippable); z, w: unused.
    bricks: vec4<u32>,
}

@group(1) @binding(0) var<uniform> mp: MapParams;
@group(1) @binding(1) var<storage, read> classes: array<u32>;
@group(1) @binding(2) var<storage, read_write> map_out: array<f32>;
@group(1) @binding(3) var<storage, read_write> cells_seen: array<atomic<u32>>;

// Marks march cell `c` in `cells_seen` (4 bits per cell, 8 per word): bit 0 = seen (it may hold
// surface and the ray entered it); bits 1-3 = a near event along x, y, z (the ray entered it
// within `hi.w` of a grid plane across that axis, so rounding may have skipped the cell on the
// other side; the CPU marks those cells, iso::render::seen_cells).
fn mark_cell(c: vec3<i32>, bits: u32) {
    if (mp.size.w == 1u) {
        let u = vec3<u32>(c);
        let i = (u.z * mp.dims.y + u.y) * mp.dims.x + u.x;
        let b = bits << ((i & 7u) * 4u);
        // Most cells are seen by many rays: a load first spares the atomic read-modify-write.
        if ((atomicLoad(&cells_seen[i >> 3u]) & b) != b) {
            atomicOr(&cells_seen[i >> 3u], b);
        }
    }
}

// The occluder node holding march cell `c`: bits 0-1 its class, bit 2 set when its fine skip
// brick (`2^bricks.x` nodes per axis) and the one-node ring around it are all of that class,
// bit 3 the same for its coarse brick (`2^bricks.y`); for single cells (`size.z` = 1) bits 4-6
// set when its low x, y, z face's 4 corners are all below or all above, bit 7 when its low
// corner is below. 8 bits per node, 4 per word (one read per step for all).
fn node_info(c: vec3<i32>) -> u32 {
    let u = vec3<u32>(c) >> vec3<u32>(mp.size.y);
    let i = (u.z * mp.occ_dims.y + u.y) * mp.occ_dims.x + u.x;
    return (classes[i >> 2u] >> ((i & 3u) * 8u)) & 0xffu;
}

// Where the ray leaves cell `c` across each axis (the DDA's next crossings), `t0 + c dt` with the
// ray's constants from `ray_exits`: a function of the cell alone, so a brick jump lands in the
// state the cell-by-cell walk would reach, bit for bit. (Two per-ray vectors rather than the
// ray's origin, inverse direction and stepping side keep the walk's loop in fewer registers.)
fn exits(c: vec3<i32>, t0: vec3<f32>, dt: vec3<f32>) -> vec3<f32> {
    return fma(vec3<f32>(c), dt, t0);
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
    let o = mp.ray_o.xyz + ndc.x * mp.ray_ox.xyz + ndc.y * mp.ray_oy.xyz;
    var d = mp.ray_d.xyz + ndc.x * mp.ray_dx.xyz + ndc.y * mp.ray_dy.xyz;
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
        // exits(c) = (lo + (c + ahead) node - o) inv, ahead = 1 along the axes the ray advances.
        let ahead = select(vec3<f32>(0.0), vec3<f32>(1.0), d > vec3<f32>(0.0));
        let xt0 = (mp.lo.xyz + ahead * mp.node.xyz - o) * inv;
        let xdt = mp.node.xyz * inv;
        var tnext = exits(c, xt0, xdt);
        var last = 0u;
        var t_enter = t0;
        var crossed = -1;
        // The node of the cell before (its low face is the one crossed when stepping down an
        // axis), and whether the last move was a single step (a brick jump crosses a face of its
        // brick's class, which changes nothing).
        var prev_info = 0u;
        var stepped = false;
        loop {
            let info = node_info(c);
            let k = info & 3u;
            // The face just crossed, inside the box: all 4 corners below (above) put it on the
            // below (above) side of the surface, as a Below (Above) cell is; a face of the other
            // class than the last seen proves the crossing before it, in the cells already
            // marked: this cell lies behind it and is not marked. The face's class: uniform (bit
            // 4 + axis of the node that owns it as its low face) and the side of that node's low
            // corner, which every one of its low faces holds (bit 7).
            let owner = select(prev_info, info, stp[clamp(crossed, 0, 2)] > 0);
            let uniform = ((owner >> (4u + u32(clamp(crossed, 0, 2)))) & 1u) == 1u;
            let face_seen = mp.size.z == 1u && stepped && uniform && t_enter > in0 && t_enter < in1;
            let fk = select(0u, select(2u, 1u, (owner & 128u) != 0u), face_seen);
            var stop = fk != 0u && last != 0u && last != fk;
            last = select(last, fk, fk != 0u);
            // Below / Above cells (uniform, NaN-free) hold no triangle: the others need their bit.
            // Where the entry point lies within `hi.w` of a grid plane other than the one just
            // crossed (whose other side the walk has marked), the ray may have skipped a cell
            // beside it by rounding: a near event, resolved on the CPU. (One mark per step and no
            // neighbour loop here: a CPU rasteriser runs every branch of the loop for every lane.)
            let gp = (o + d * t_enter - mp.lo.xyz) / mp.node.xyz;
            let close = abs(gp - floor(gp + 0.5)) < vec3<f32>(mp.hi.w) & (vec3<i32>(0, 1, 2) != vec3<i32>(crossed));
            let nb = select(vec3<u32>(0u), vec3<u32>(2u, 4u, 8u), close);
            let bits = select(0u, 1u, (k == 0u || k == 3u) && !stop) | nb.x | nb.y | nb.z;
            if (bits != 0u) {
                mark_cell(c, bits);
            }
            // A NaN cell, or a cell met only in the margin outside the box, breaks every pair.
            if (k == 3u || min(min(tnext.x, tnext.y), tnext.z) <= in0 || t_enter >= in1) {
                last = 0u;
            } else if (k != 0u) {
                stop = stop || (last != 0u && last != k);
                last = k;
            }
            if (stop) {
                let q = o + d * (t_enter + mp.lo.w / length(d));
                let clip = g.view_proj * vec4<f32>(q, 1.0);
                result = clamp(clip.z / clip.w, 0.0, 1.0);
                break;
            }
            // One step: to the next cell, or, in a skip brick of class `last` (it and its ring all
            // of that class: the walk would mark nothing in it and never stop), to where the ray
            // leaves the brick (`last == k`: the cell counted; `k` is then Below or Above). A
            // coarse brick is skippable only if its fine bricks are. A step is a brick of one
            // cell (`s` = 0), so both run the same code.
            let skip = mp.bricks.x != 0u && last == k && k != 0u && (info & 4u) != 0u;
            let s = select(0u, mp.size.y + select(mp.bricks.x, mp.bricks.y, (info & 8u) != 0u), skip);
            // The brick's last cell along the ray on each axis, and where the ray leaves it (ties
            // to the lower axis).
            let blo = (c >> vec3<u32>(s)) << vec3<u32>(s);
            let e = select(blo, min(blo + vec3<i32>((1 << s) - 1), dims - 1), stp > vec3<i32>(0));
            let x = exits(e, xt0, xdt);
            let a01 = select(0, 1, x.y < x.x);
            let a = select(a01, 2, x.z < min(x.x, x.y));
            let tx = x[a];
            if (tx >= t1) {
                break;
            }
            // The other axes advance while their crossing comes first (a tie goes to the lower
            // axis), at most to the brick's last cell (`s` = 0: none does). The crossings
            // `exits(c + j stp)` grow with `j`, so the count is the estimate `(tx - tnext) / |dt|`
            // corrected by one either way: the loop that counted them one by one, in closed form
            // (a CPU rasteriser runs a loop's first round for every lane whether any needs it).
            let axis = vec3<i32>(0, 1, 2);
            let lower = axis < vec3<i32>(a);
            let most = abs(e - c);
            var n = vec3<i32>(clamp(ceil((tx - tnext) / abs(xdt)), vec3<f32>(0.0), vec3<f32>(most)));
            let xb = exits(c + (n - 1) * stp, xt0, xdt);
            n -= select(vec3<i32>(0), vec3<i32>(1), n > vec3<i32>(0) & !(xb < vec3<f32>(tx) | (xb == vec3<f32>(tx) & lower)));
            let xn = exits(c + n * stp, xt0, xdt);
            n += select(vec3<i32>(0), vec3<i32>(1), n < most & (xn < vec3<f32>(tx) | (xn == vec3<f32>(tx) & lower)));
            c = select(c + n * stp, e + stp, axis == vec3<i32>(a));
            tnext = exits(c, xt0, xdt);
            t_enter = tx;
            crossed = a;
            prev_info = info;
            stepped = s == 0u;
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
