// Depth-tie priorities (scene::Object::priority), shared by the scene passes (after common.wgsl)
// and the box tests (after box.wgsl): both declare `g` with `ortho_near`.

// One priority step: 2^-21 of an object's distance (scene::PRIORITY_DEPTH_STEP).
const PRIORITY_STEP: f32 = 4.76837158203125e-7;

// `clip` as if the fraction `k` of its distance nearer: perspective depth (near / distance) scaled
// by 1 + k; orthographic depth (linear from the far plane, 0, to the near plane, 1) moved by k
// times the distance in depth units (ortho_near + 1 - depth). Never pushed past the near plane
// (depth 1): a surface on it (an automatic near plane fits the scene) stays drawn, where
// priorities cannot order it; what lies before it is clipped as ever.
fn nearer_by(clip: vec4<f32>, k: f32) -> vec4<f32> {
    var z = clip.z * (1.0 + k);
    if (g.ortho_near >= 0.0) {
        z = clip.z + k * (g.ortho_near * clip.w + clip.w - clip.z);
    }
    return vec4<f32>(clip.xy, select(min(z, clip.w), clip.z, clip.z > clip.w), clip.w);
}
