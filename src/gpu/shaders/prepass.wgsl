// Depth + tile-id prepass of coarse proxies (common.wgsl is prepended): only the tile id, for the
// exact per-tile visible-pixel histogram.

@fragment
fn fs_id(v: VOut) -> @location(0) u32 {
    return v.tile + 1u;
}
