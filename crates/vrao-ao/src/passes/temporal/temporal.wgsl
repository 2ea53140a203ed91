// Temporal accumulation of the occlusion by reverse reprojection (Lin's NCTU thesis §3.1). Each
// occlusion pixel is carried to where its surface point was in the previous frame
// (C = P_{t−1} V_{t−1} W_t); the history there is reused when it holds the same point,
// ‖W_t − W_{t−1}‖ ≤ ε (Lin's NCTU thesis eq. 3, plus two pixel footprints at the pixel's
// distance), and blended with this frame's value. The technique turns its sampling
// pattern each frame, so the blend averages different patterns. Disoccluded,
// off-screen or non-finite history is discarded: the pixel starts again from this frame.
//
// In a scene that moves, each pixel is carried back by its motion vector instead (the
// G-buffer's, or a host's): its surface point's previous position is rebuilt from the
// previous uv and distance, so a moving object keeps its own history. A surface near a
// moving object keeps its place but not its occlusion: within the AO radius of a moving
// object (where it is or was) the history is clamped to this frame's 3×3 neighbourhood
// and kept short, so the occlusion the object cast where it was does not linger.

struct Temporal {
    // Current frame, per layer: view space → the scene's anchored world frame.
    anchored_from_view: array<mat4x4<f32>, 2>,
    // Previous frame, per layer: anchored world frame → clip space.
    previous_clip_from_anchored: array<mat4x4<f32>, 2>,
    epsilon: f32,
    confidence_bias: f32,
    max_frames: f32,
    // 0: running mean of up to max_frames frames; 1: the confidence blend of Lin's NCTU thesis.
    blend: u32,
    // 0 when there is no usable previous frame (first frame, settings changed).
    history_valid: u32,
    // Tangent span of one occlusion pixel (for the footprint term of ε).
    pixel_tangent: f32,
    // Motion-adaptive window (settings.rs `Temporal::motion_px`); 0 = off.
    motion_px: f32,
    // 1 when `motion` holds per-pixel motion this frame.
    has_motion: u32,
    // Previous frame, per layer: view space → anchored world frame, and its tangents.
    previous_anchored_from_view: array<mat4x4<f32>, 2>,
    previous_tangents: array<vec4<f32>, 2>,
    // Previous frame, per layer: anchored world frame → view space.
    previous_view_from_anchored: array<mat4x4<f32>, 2>,
    // Boxes around the moving objects, now and before.
    movers: array<MoverBox, MAX_MOVERS>,
    mover_count: u32,
    // 1: the motion's z is the change in distance and w its validity (the G-buffer's);
    // 0: a host's 2D vectors, the distance follows the eyes' motion.
    motion_with_distance: u32,
    // Turns a motion texel's xy into the uv offset to the previous frame.
    motion_uv_scale: vec2<f32>,
};

// A box around a moving object: rows map the anchored frame to the box's (orthonormal),
// half_extents.xyz its half size, half_extents.w the AO radius it reaches by.
struct MoverBox {
    rows: array<vec4<f32>, 3>,
    half_extents: vec4<f32>,
};

const MAX_MOVERS: u32 = 16u;
// The longest history near a moving object.
const NEAR_MOVER_WINDOW: f32 = 2.0;

// The shortest window motion may impose: below it the mean barely removes noise.
const MIN_MOTION_WINDOW: f32 = 4.0;

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> ao: AoParams;
@group(0) @binding(2) var<uniform> temporal: Temporal;
@group(0) @binding(3) var geometry_layers: texture_2d_array<f32>;
@group(0) @binding(4) var current_layers: texture_2d_array<f32>;
@group(0) @binding(5) var history_value: texture_2d_array<f32>;
@group(0) @binding(6) var history_position: texture_2d_array<f32>;
@group(0) @binding(7) var accumulated_out: ChainTarget;
@group(0) @binding(8) var history_value_out: ChainTarget;
@group(0) @binding(9) var history_position_out: texture_storage_2d_array<rgba32float, write>;
@group(0) @binding(10) var motion: texture_2d_array<f32>;

// Whether `world` lies within a moving object's reach (the AO radius around its box).
fn near_mover(world: vec3<f32>) -> bool {
    let p = vec4<f32>(world, 1.0);
    for (var i = 0u; i < min(temporal.mover_count, MAX_MOVERS); i++) {
        let m = temporal.movers[i];
        let local = vec3<f32>(dot(m.rows[0], p), dot(m.rows[1], p), dot(m.rows[2], p));
        let outside = max(abs(local) - m.half_extents.xyz, vec3<f32>(0.0));
        if (length(outside) <= m.half_extents.w) {
            return true;
        }
    }
    return false;
}

fn all_finite4(v: vec4<f32>) -> bool {
    return all(v == v) && all(abs(v) <= vec4<f32>(3.0e38));
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= ao.ao_size.x || id.y >= ao.ao_size.y || id.z >= frame.layers) {
        return;
    }
    let p = vec2<i32>(id.xy);
    let layer = i32(id.z);
    if (tile_rate(id.xy, id.z, ao.scale) == 0.0) {
        // Hidden by the lens (visibility.wgsl): unoccluded, as the sky, and no history.
        textureStore(accumulated_out, p, layer, chain_texel(vec4<f32>(0.0, 0.0, 0.0, 1.0)));
        textureStore(history_value_out, p, layer, chain_texel(vec4<f32>(0.0, 0.0, 0.0, 1.0)));
        textureStore(history_position_out, p, layer, vec4<f32>(0.0));
        return;
    }
    let current = chain_value(textureLoad(current_layers, p, layer, 0));
    let geometry = textureLoad(geometry_layers, p, layer, 0);
    if (!(geometry.w > 0.0)) {
        // Sky: nothing to accumulate.
        textureStore(accumulated_out, p, layer, chain_texel(current));
        textureStore(history_value_out, p, layer, chain_texel(current));
        textureStore(history_position_out, p, layer, vec4<f32>(0.0));
        return;
    }
    let eye = frame.eyes[id.z];
    let uv = pixel_uv(full_res_pixel(id.xy, ao.scale, frame.size), frame.size);
    let view_position = view_position_from_distance(uv, geometry.w, eye.tangents);
    let world = (temporal.anchored_from_view[id.z] * vec4<f32>(view_position, 1.0)).xyz;

    var count = 0.0;
    var previous = vec4<f32>(0.0);
    var window = temporal.max_frames;
    let near_moving = near_mover(world);
    if (temporal.history_valid != 0u) {
        // Where the point was: by the eye's motion alone in a still scene, by the pixel's
        // motion vector in one that moves.
        var previous_uv = vec2<f32>(-1.0);
        var previous_world = world;
        if (temporal.has_motion != 0u) {
            let full = full_res_pixel(id.xy, ao.scale, frame.size);
            let m = textureLoad(motion, vec2<i32>(full), layer, 0);
            let with_distance = temporal.motion_with_distance != 0u;
            let valid = select(all(m.xy == m.xy) && all(abs(m.xy) < vec2<f32>(3.0e38)), m.w > 0.0, with_distance);
            if (valid) {
                previous_uv = uv + m.xy * temporal.motion_uv_scale;
                var previous_distance = geometry.w + m.z;
                if (!with_distance) {
                    previous_distance = -(temporal.previous_view_from_anchored[id.z] * vec4<f32>(world, 1.0)).z;
                }
                let before = view_position_from_distance(previous_uv, previous_distance, temporal.previous_tangents[id.z]);
                previous_world = (temporal.previous_anchored_from_view[id.z] * vec4<f32>(before, 1.0)).xyz;
            }
        } else {
            let clip = temporal.previous_clip_from_anchored[id.z] * vec4<f32>(world, 1.0);
            if (clip.w > 0.0) {
                let ndc = clip.xy / clip.w;
                previous_uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
            }
        }
        if (all(previous_uv >= vec2<f32>(0.0)) && all(previous_uv < vec2<f32>(1.0))) {
            let q = min(vec2<i32>(previous_uv * vec2<f32>(ao.ao_size)), vec2<i32>(ao.ao_size) - vec2<i32>(1));
            let stored = textureLoad(history_position, q, layer, 0);
            let value = chain_value(textureLoad(history_value, q, layer, 0));
            let footprint = geometry.w * temporal.pixel_tangent;
            let same_point = distance(stored.xyz, previous_world) <= temporal.epsilon + 2.0 * footprint;
            if (stored.w >= 1.0 && same_point && all_finite4(stored) && all_finite4(value)) {
                count = stored.w;
                previous = value;
                if (temporal.motion_px > 0.0) {
                    let moved = length((previous_uv - uv) * vec2<f32>(ao.ao_size));
                    let shortened = temporal.max_frames / (1.0 + moved / temporal.motion_px);
                    window = clamp(shortened, min(MIN_MOTION_WINDOW, temporal.max_frames), temporal.max_frames);
                }
                if (near_moving) {
                    // The occlusion here changes as the object moves: keep the history
                    // only within this frame's neighbourhood, and short.
                    var low = current;
                    var high = current;
                    for (var dy = -1; dy <= 1; dy++) {
                        for (var dx = -1; dx <= 1; dx++) {
                            let n = clamp(p + vec2<i32>(dx, dy), vec2<i32>(0), vec2<i32>(ao.ao_size) - vec2<i32>(1));
                            let v = chain_value(textureLoad(current_layers, n, layer, 0));
                            low = min(low, v);
                            high = max(high, v);
                        }
                    }
                    previous = clamp(previous, low, high);
                    window = min(window, NEAR_MOVER_WINDOW);
                }
            }
        }
    }

    var result = current;
    if (count >= 1.0) {
        if (temporal.blend == 0u) {
            // Running mean: the history holds the mean of `count` frames, of which at
            // most window − 1 are kept (the count stored below is what was kept).
            count = min(count, window - 1.0);
            result = previous + (current - previous) / (count + 1.0);
        } else {
            let confidence = 1.0 - clamp(abs(previous.a - current.a), 0.0, 1.0) / (1.0 + temporal.confidence_bias);
            result = confidence * previous + (1.0 - confidence) * current;
        }
    }
    result = vec4<f32>(finite_or_zero3(result.rgb), saturate_ao(result.a));
    let next_count = min(count + 1.0, temporal.max_frames);
    textureStore(accumulated_out, p, layer, chain_texel(result));
    textureStore(history_value_out, p, layer, chain_texel(result));
    textureStore(history_position_out, p, layer, vec4<f32>(world, next_count));
}
