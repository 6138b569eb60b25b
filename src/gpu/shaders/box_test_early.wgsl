// The box test's fragment on the hardware's early depth test (appended to box.wgsl +
// box_test.wgsl, whose vertex stage it uses): the image's depth is the read-only depth attachment,
// compared GreaterEqual (at or in front, reverse-Z) before the fragment runs, so only the
// fragments that box_test.wgsl's fs_box would count reach the atomic. Only on devices with
// SHADER_EARLY_DEPTH_TEST that rasterise reverse-Z depth exactly (not GL: see common.wgsl).
@fragment
@early_depth_test(force)
fn fs_box_early(v: BoxOut) -> @location(0) u32 {
    atomicAdd(&counts[v.tile], 1u);
    return 0u;
}
