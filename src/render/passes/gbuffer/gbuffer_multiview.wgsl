// G-buffer vertex entry for multiview: one draw reaches both eye layers.
@vertex
fn vs_main(v: VertexIn, @builtin(view_index) view: u32) -> VertexOut {
    return transform_vertex(v, view);
}
