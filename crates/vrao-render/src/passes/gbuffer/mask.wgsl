// The lens's hidden pixels into depth around the G-buffer (gbuffer/mask.rs): a full-screen
// triangle per eye layer (its index as the instance) that keeps only the pixels the
// visibility mask hides. Before the scene it writes the nearest depth there, so the
// scene's fragments fail the depth test before shading; after, the farthest (the sky's),
// so the compute passes see no surface there (a march reaching into the hidden band
// finds nothing to occlude) and the composite paints them black.

@group(0) @binding(0) var visibility_rates: texture_2d_array<f32>;
@group(0) @binding(1) var visibility_pixels: texture_2d_array<f32>;

struct MaskVertex {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) layer: u32,
};

fn full_screen(index: u32, layer: u32, depth: f32) -> MaskVertex {
    let corner = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    var out: MaskVertex;
    out.position = vec4<f32>(corner * 2.0 - 1.0, depth, 1.0);
    out.layer = layer;
    return out;
}

// Reversed Z: 1 is the near plane, in front of everything.
@vertex
fn vs_near(@builtin(vertex_index) index: u32, @builtin(instance_index) layer: u32) -> MaskVertex {
    return full_screen(index, layer, 1.0);
}

// 0 is infinitely far: the sky.
@vertex
fn vs_far(@builtin(vertex_index) index: u32, @builtin(instance_index) layer: u32) -> MaskVertex {
    return full_screen(index, layer, 0.0);
}

@fragment
fn fs_hidden(in: MaskVertex) {
    if (textureLoad(visibility_pixels, vec2<i32>(in.position.xy), i32(in.layer), 0).r > 0.5) {
        discard;
    }
}
