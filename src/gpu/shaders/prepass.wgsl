// Depth + tile-id prepass of coarse proxies (common.wgsl is prepended): only the tile id, for the
// exact per-tile visible-pixel histogram.

@fragment
fn fs_id(v: VOut) -> @location(0) u32 {
    return v.tile + 1u;
}

struct IdOutGl {
    @location(0) id: u32,
    @builtin(frag_depth) depth: f32,
}

// GL: the same, with frag_depth written (see VOutGl in common.wgsl).
@fragment
fn fs_id_gl(v: VOutGl) -> IdOutGl {
    return IdOutGl(v.tile + 1u, gl_depth(v));
}
