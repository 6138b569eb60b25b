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
// sample (outside the domain: resets the walk). With single cells the faces the ray crosses
// count too: a uniform face (its corners all below or above) by its class bits, any face point
// by the face's contour when the samples are bound (`contour_side`).
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
    // The faces' contours (single cells, `CONTOURS`): x = where the sample blocks start in
    // `contour_data` (the walk finds the side of the surface of every face point it crosses in a
    // brick that holds surface); y, z: contour bricks along x and y; w: the isovalue's bits (f32).
    contour: vec4<u32>,
    // Skip bricks (iso/bricks.rs): x, y: log2 of the fine and the coarse bricks' size in occluder
    // nodes (x = 0: no skipping; the nodes' flags say which bricks are skippable); z, w: unused.
    bricks: vec4<u32>,
}

// Whether the walk places the faces' contours (`contour_data` bound): a pipeline constant, so the
// walk without them carries none of their code (a CPU rasteriser runs it for every lane).
override CONTOURS: bool = false;

@group(1) @binding(0) var<uniform> mp: MapParams;
@group(1) @binding(1) var<storage, read> classes: array<u32>;
@group(1) @binding(2) var<storage, read_write> map_out: array<f32>;
@group(1) @binding(3) var<storage, read_write> cells_seen: array<atomic<u32>>;
// The contour bricks (iso/bricks.rs `contour_bricks`): per brick of 4³ cells (x fastest) the
// index of its block of 5³ samples (f32 bits, x fastest) or 0xffffffff, then the blocks.
@group(1) @binding(4) var<storage, read> contour_data: array<u32>;

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
// corner is below. 8 bits per node, 4 per word (one read per step for all), in bricks of 4³
// nodes, 64 bytes each (iso/bricks.rs `pack_nodes`: a step mostly stays in a cache line read).
fn node_info(c: vec3<i32>) -> u32 {
    let u = vec3<u32>(c) >> vec3<u32>(mp.size.y);
    let nb = (mp.occ_dims.xy + 3u) >> vec2<u32>(2u);
    let b = u >> vec3<u32>(2u);
    let l = u & vec3<u32>(3u);
    let i = ((((b.z * nb.y + b.y) * nb.x + b.x) << 6u) | (l.z << 4u) | (l.y << 2u)) + l.x;
    return (classes[i >> 2u] >> (l.x * 8u)) & 0xffu;
}

// The side of the marching-cubes surface of point `uv` (in [0, 1]^2) of a cell face whose corners
// (u, v) = (0, 0), (1, 0), (0, 1), (1, 1) have the values `f` minus the isovalue: 1 = below,
// 2 = above, 0 = not known. A corner is above when its value is >= the isovalue (march/cases.rs).
// The surface meets the face only along its contour: segments between the crossing points of
// the face's edges, placed as the extraction places its vertices (`t = f_a / (f_a - f_b)` from
// the lower corner). Known: the whole face when no edge crosses; the corner's side inside the
// triangle a corner cuts off (both its edges cross: the odd corner of a face with one corner
// unlike the others, or any corner of an ambiguous face, whose triangles do not depend on how
// the extraction joins the face's centre); the rest of the face when one corner is cut off; each
// side of the one segment across a face with two corners on each side. Not known: the middle
// of an ambiguous face, a face with a corner at the isovalue (its vertices may sit on that
// corner), or a point whose ray passes within `m` (grid units) of a segment's line: the
// rasteriser's rounding may put its pixel on either side. (A ray that grazes the face passes
// that near a segment far from where it meets the face: `ray` is its direction in grid units,
// along u, v and the face's normal; a point `g` from the line within the face is `g |n| /
// sqrt(n^2 + p^2)` from it across space, `n` and `p` the ray's components along the face's
// normal and the line's normal in the face.)
fn contour_side(f: vec4<f32>, uv: vec2<f32>, ray: vec3<f32>, m: f32) -> u32 {
    let k = select(vec4<u32>(1u), vec4<u32>(2u), f >= vec4<f32>(0.0));
    // The edges v = 0 (corners 0-1), v = 1 (2-3), u = 0 (0-2), u = 1 (1-3), from their lower corner.
    let ea = vec4<f32>(f.x, f.z, f.x, f.y);
    let eb = vec4<f32>(f.y, f.w, f.z, f.w);
    let cr = (ea >= vec4<f32>(0.0)) != (eb >= vec4<f32>(0.0));
    let t = select(vec4<f32>(0.5), ea / (ea - eb), cr);
    let u = uv.x;
    let v = uv.y;
    // Each corner's triangle in coordinates mirrored to put the corner at the origin: signed
    // distance from the segment between its crossings (negative on the corner's side).
    let px = vec4<f32>(u, 1.0 - u, u, 1.0 - u);
    let py = vec4<f32>(v, v, 1.0 - v, 1.0 - v);
    let tx = vec4<f32>(t.x, 1.0 - t.x, t.y, 1.0 - t.y);
    let ty = vec4<f32>(t.z, t.w, 1.0 - t.z, 1.0 - t.w);
    // Each line as `G = 0` with `G` affine in (u, v) and gradient `q`: a point is known when
    // `G^2 n^2 > m^2 (n^2 |q|^2 + (q . ray)^2)` (no root taken), on the side of `G`'s sign.
    let n2 = ray.z * ray.z;
    let m2 = m * m;
    let g = px * ty + py * tx - tx * ty;
    let qr = ty * vec4<f32>(ray.x, -ray.x, ray.x, -ray.x) + tx * vec4<f32>(ray.y, ray.y, -ray.y, -ray.y);
    let far = g * g * n2 > m2 * (n2 * (tx * tx + ty * ty) + qr * qr);
    let both = vec4<bool>(cr.x && cr.z, cr.x && cr.w, cr.y && cr.z, cr.y && cr.w);
    let cut = select(vec4<u32>(0u), vec4<u32>(1u), both);
    let inside = both & far & (g < vec4<f32>(0.0));
    var r = select(select(select(select(0u, k.w, inside.w), k.z, inside.z), k.y, inside.y), k.x, inside.x);
    // One corner cut off: beyond its segment lies the other side.
    let odd = dot(cut, vec4<u32>(1u)) == 1u;
    r = select(r, 3u - dot(cut, k), odd && any(both & far & (g > vec4<f32>(0.0))));
    // Two corners on each side: one segment, from (0, t.z) to (1, t.w) or from (t.x, 0) to (t.y, 1).
    let sv = t.w - t.z;
    let su = t.y - t.x;
    let gv = v - t.z - u * sv;
    let gu = u - t.x - v * su;
    let qv = ray.y - sv * ray.x;
    let qu = ray.x - su * ray.y;
    let far_v = gv * gv * n2 > m2 * (n2 * (1.0 + sv * sv) + qv * qv);
    let far_u = gu * gu * n2 > m2 * (n2 * (1.0 + su * su) + qu * qu);
    let across_v = cr.z && cr.w && !cr.x && !cr.y && far_v;
    let across_u = cr.x && cr.y && !cr.z && !cr.w && far_u;
    r = select(r, select(k.z, k.x, gv < 0.0), across_v);
    r = select(r, select(k.y, k.x, gu < 0.0), across_u);
    r = select(r, k.x, !any(cr));
    return select(r, 0u, any(f == vec4<f32>(0.0)));
}

// The index of the contour brick (4³ cells) holding cell `c` in `contour_data`'s table.
fn contour_brick(c: vec3<i32>) -> u32 {
    let cb = vec3<u32>(c) >> vec3<u32>(2u);
    return (cb.z * mp.contour.z + cb.y) * mp.contour.y + cb.x;
}

// The side of the surface (`contour_side`) of the point `gp` (grid units) of the face the walk
// crossed along axis `a` into cell `c` (`up`: moving up that axis, so it is the cell's low face),
// the ray's direction `dg` (grid units), `block` the entry of the cell's contour brick; 4
// (unknown to this test) when the brick holds no passable cell: its faces are uniform (the class
// bits settle them) or touch NaN. (lavapipe reads a storage buffer lane by lane, each read
// costing a round per lane: the samples are read only by the lanes that need them.)
fn face_side(c: vec3<i32>, a: i32, up: bool, gp: vec3<f32>, dg: vec3<f32>, block: u32) -> u32 {
    if (block == 0xffffffffu) {
        return 4u;
    }
    let b = (a + 1) % 3;
    let e = (a + 2) % 3;
    // The face's low corner in the brick's block of 5³ samples.
    var q = vec3<u32>(c) & vec3<u32>(3u);
    q[a] += select(1u, 0u, up);
    let st = vec3<u32>(1u, 5u, 25u);
    let i = mp.contour.x + block * 125u + dot(q, st);
    let sample = vec4<u32>(contour_data[i], contour_data[i + st[b]], contour_data[i + st[e]], contour_data[i + st[b] + st[e]]);
    let f = bitcast<vec4<f32>>(sample) - vec4<f32>(bitcast<f32>(mp.contour.w));
    return contour_side(f, vec2<f32>(gp[b] - f32(c[b]), gp[e] - f32(c[e])), vec3<f32>(dg[b], dg[e], dg[a]), mp.hi.w);
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
    // Along an axis the ray runs parallel to, it never leaves its cell (below: the crossings at
    // 1e30); a tiny direction would make a ray lying on a plane, say the box's top face in an
    // axis-aligned orthographic view, leave its cell at once and the walk end there.
    let parallel = abs(d) < vec3<f32>(1e-30);
    d = select(d, vec3<f32>(1e-30), parallel);
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
        let xt0 = select((mp.lo.xyz + ahead * mp.node.xyz - o) * inv, vec3<f32>(1e30), parallel);
        let xdt = select(mp.node.xyz * inv, vec3<f32>(0.0), parallel);
        var tnext = exits(c, xt0, xdt);
        // The ray in grid units (march cells): `gp = og + t dg`.
        let dg = d / mp.node.xyz;
        let og = (o - mp.lo.xyz) / mp.node.xyz;
        // The box's far planes in grid units (march cells may overhang it).
        let ext = (mp.hi.xyz - mp.lo.xyz) / mp.node.xyz;
        var last = 0u;
        var t_enter = t0;
        var crossed = -1;
        // The node of the cell before (its low face is the one crossed when stepping down an
        // axis), and whether the last move was a single step (a brick jump crosses a face of its
        // brick's class, which changes nothing).
        var prev_info = 0u;
        var stepped = false;
        // The contour brick last read (`contour_brick`) and its entry.
        var brick_at = 0xffffffffu;
        var brick = 0xffffffffu;
        loop {
            let info = node_info(c);
            let k = info & 3u;
            // The face just crossed, inside the box: all 4 corners below (above) put it on the
            // below (above) side of the surface, as a Below (Above) cell is; a face of the other
            // class than the last seen proves the crossing before it, in the cells already
            // marked: this cell lies behind it and is not marked. The face's class: uniform (bit
            // 4 + axis of the node that owns it as its low face) and the side of that node's low
            // corner, which every one of its low faces holds (bit 7).
            let ax = clamp(crossed, 0, 2);
            let up = stp[ax] > 0;
            let owner = select(prev_info, info, up);
            let uniform = ((owner >> (4u + u32(ax))) & 1u) == 1u;
            let face_in = mp.size.z == 1u && stepped && t_enter > in0 && t_enter < in1;
            let gp = fma(dg, vec3<f32>(t_enter), og);
            var fk = select(0u, select(2u, 1u, (owner & 128u) != 0u), face_in && uniform);
            // With the samples at hand, any face point's side (a mixed face's too): the walk stops
            // right behind the surface instead of at the next uniform face.
            // (A uniform face's contour is its class: only mixed faces need their samples. The
            // brick's entry is read again only when the walk enters another brick.)
            if (CONTOURS && face_in && !uniform) {
                let cb = contour_brick(c);
                if (cb != brick_at) {
                    brick = contour_data[cb];
                    brick_at = cb;
                }
                let side = face_side(c, ax, up, gp, dg, brick);
                fk = select(side, fk, side == 4u);
            }
            // The surface has a boundary on the box's faces, and a ray within rounding distance
            // of it may be drawn past it: no proof ends at a point within the margin of a box
            // face, and none starts before a cell that may hold surface entered there. (A ray's
            // distance to a plane is linear, so a crossing that near a box face lies in a cell
            // entered or left that near it; uniform cells hold no surface, so skip bricks stay
            // exact.)
            let at_box = any((abs(gp) < vec3<f32>(mp.hi.w)) | (abs(gp - ext) < vec3<f32>(mp.hi.w)));
            var stop = fk != 0u && last != 0u && last != fk && !at_box;
            last = select(last, fk, fk != 0u);
            // Below / Above cells (uniform, NaN-free) hold no triangle: the others need their bit.
            // Where the entry point lies within `hi.w` of a grid plane other than the one just
            // crossed (whose other side the walk has marked), the ray may have skipped a cell
            // beside it by rounding: a near event, resolved on the CPU. (One mark per step and no
            // neighbour loop here: a CPU rasteriser runs every branch of the loop for every lane.)
            let close = abs(gp - floor(gp + 0.5)) < vec3<f32>(mp.hi.w) & (vec3<i32>(0, 1, 2) != vec3<i32>(crossed));
            let nb = select(vec3<u32>(0u), vec3<u32>(2u, 4u, 8u), close);
            let bits = select(0u, 1u, (k == 0u || k == 3u) && !stop) | nb.x | nb.y | nb.z;
            if (bits != 0u) {
                mark_cell(c, bits);
            }
            // A NaN cell (or one next to NaN, `bricks::dilate_nan`), a cell that may hold surface
            // entered within the margin of the box's faces, or one met only in the margin outside
            // the box, breaks every pair.
            if (k == 3u || (at_box && k == 0u) || min(min(tnext.x, tnext.y), tnext.z) <= in0 || t_enter >= in1) {
                last = 0u;
            } else if (k != 0u) {
                stop = stop || (last != 0u && last != k && !at_box);
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
