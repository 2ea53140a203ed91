// G-buffer vertex entries for multiview: one draw reaches both eye layers.
@vertex
fn vs_main(v: VertexIn, @builtin(view_index) view: u32) -> VertexOut {
    return transform_vertex(v, view);
}

@vertex
fn vs_motion(v: VertexIn, @builtin(view_index) view: u32) -> MotionVertexOut {
    return transform_vertex_with_motion(v, view);
}
