// G-buffer vertex entry for one pass per eye: the pass binds the eye it renders.
struct EyeSelect {
    index: u32,
};
@group(2) @binding(0) var<uniform> eye_select: EyeSelect;

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    return transform_vertex(v, eye_select.index);
}
