// G-buffer vertex entries for one pass per eye: the pass binds the eye it renders.
struct EyeSelect {
    index: u32,
};
@group(2) @binding(0) var<uniform> eye_select: EyeSelect;

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    return transform_vertex(v, eye_select.index);
}

@vertex
fn vs_motion(v: VertexIn) -> MotionVertexOut {
    return transform_vertex_with_motion(v, eye_select.index);
}
