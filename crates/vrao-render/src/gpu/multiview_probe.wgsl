// Start-up probe: one oversized triangle drawn with multiview must cover every layer.
// Some drivers (Mesa lavapipe 22.x) send triangles that need clipping to layer 0 only.

@vertex
fn vs_main(@builtin(vertex_index) i: u32, @builtin(view_index) view: u32) -> @builtin(position) vec4<f32> {
    // A triangle three times the viewport, slightly different per view so both views clip.
    let corner = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)) * 3.0 - vec2<f32>(1.0 + f32(view) * 0.25);
    return vec4<f32>(corner, 0.5, 1.0);
}

@fragment
fn fs_main() -> @location(0) vec4<f32> {
    return vec4<f32>(1.0);
}
