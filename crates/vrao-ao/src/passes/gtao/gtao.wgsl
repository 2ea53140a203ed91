// GTAO with a visibility bitmask: the cosine-weighted visibility within the radius r
// (the hard cut-off target), estimated over screen-space slices (Jimenez et al. 2016,
// "Practical Real-Time Strategies for Accurate Indirect Occlusion"; Intel's XeGTAO), each
// slice's occluded directions kept as a 32-sector bitmask with a finite thickness behind
// every depth sample (Therrien, Levesque and Gilet 2023, "Screen Space Indirect Lighting
// with Visibility Bitmask").
//
// A slice is the plane through the eye, the pixel's surface point P and a screen
// direction; its directions are the angles θ from the view vector V (towards the eye),
// the hemisphere about the normal spanning θ ∈ [γ − π/2, γ + π/2] where γ is the angle
// of the normal projected into the slice. The slice's share of the cosine-weighted
// integral has density |sin θ| cos(θ − γ) (GTAO's slice form), so the sectors are laid
// out uniformly in its cumulative weight u(θ) ∈ [0, 1]: every bit weighs the same, and
// the visible fraction of a slice is the share of clear bits. A flat open surface sets no
// bit and reads exactly 1 (the slices are summed as a ratio of visible to total weight).
//
// Along each half of a slice, `steps` depth samples within r (screen distances spread by
// `step_power`, jittered per pixel) each block the angles of a slab from the visible
// surface back to `thickness` × r behind it (clipped at r). Two successive samples on
// one continuous surface (their distances closer than `connect` × r) also block the
// angles between them: a ray that is in front of a continuous surface at one sample
// and behind it at the next crosses it in between. A solid sample also blocks the
// middle `footprint` share of its stratum (the stretch of the half-slice its jittered
// position stands for) on its own surface's plane: few samples step over thin occluders,
// and a point alone read them light. A sample on an alpha-tested surface (a card,
// `THIN_CARDS`) blocks its whole stratum on the card's plane instead, and no slab.
//
// Samples that leave the eye's image through its inner border are looked up in the other
// eye's layer (occlusion.wgsl `surface_at`, guessing the last sample's distance). The
// marching eye runs as two dispatches of this file: the band of `gtao.inner_band` columns
// along its inner border with those lookups compiled in (INNER_BAND = true), and the
// rest of the image without them. The lookups' code, even never taken, made every
// pixel's march about half as slow again. A march from the rest of the image that would
// cross the inner border (a surface so near that the radius spans more than the band) is
// deferred: listed, and marched after by the band's code over the list (CROSSING), so
// the band's edge leaves no seam however near the surface.
// With two views and `stereo_reuse`, the right eye then runs as a classifying dispatch
// and an indirect one over the pixels it listed (RIGHT_EYE). Or, folded
// (`GtaoSettings::fold_right_eye`), its pixels the left eye cannot give are listed first
// (`right_eye_reuse`, from the depth alone) and marched in the left eye's dispatch, after
// its tiles (FOLDED: one indirect dispatch, so a wide GPU runs the few right-eye marches
// beside the left eye's instead of in a second dispatch of their own that lasts as long
// as its longest march); then `right_eye_reuse` copies the rest.

// Bindings and `begin_receiver`: occlusion.wgsl.
// The light a march gathers besides the visibility (`begin_light`, `gather_sample` for
// each sample's newly covered sectors, `end_slice`, `light_result`, `open_light`,
// `reused_light`) comes from the file compiled after this one: gtao_light.wgsl for GTAO
// (none: rgb 0, code the compiler drops), passes/ssdo/ssdo.wgsl for SSDO, which marches
// the same slices and sectors.

const SECTORS: f32 = 32.0;

// Whether this dispatch covers the inner-border band (with the other-eye lookups) or
// the rest of the image.
override INNER_BAND: bool = false;

// The right eye's dispatches (RIGHT_EYE, LISTED_PIXELS, `classify_right_eye`; folded,
// `right_eye_reuse`):
// occlusion/right_eye.wgsl, compiled before this file.

// Set when the scene has alpha-tested materials. A depth sample on one (the G-buffer's
// normal w, gbuffer.wgsl) is a card — a leaf, a grille, a fence — with no depth behind
// it: instead of a slab it blocks its footprint on the card's plane (`add_sample`).
// As a slab `thickness` × r deep, a grille 25 cm over a floor read as a half-metre block
// (the floor under its holes far darker than the reference's; docs/records/2026-11-29/measurements-in-code.md,
// gtao-thin-cards). Off, no pixel pays the normal's fetch.
override THIN_CARDS: bool = false;
// Set when a second depth layer is bound (`AoSettings::layers` = 2, and one can be had:
// passes/gtao/mod.rs): each depth sample also fetches the second layer at its pixel, and
// where it holds a surface the sample blocks the span from the first surface to it
// (`add_sample`), the thickness only where it holds none. Off, no pixel pays the fetch
// and the march is today's to the bit.
override SECOND_LAYER: bool = false;
// Set where `gtao.footprint` > 0: solid samples block their footprint (`add_sample`). Off,
// no pixel pays the normal's fetch or the footprint's ends.
override FOOTPRINT: bool = false;
@group(0) @binding(12) var second_depth_layers: texture_depth_2d_array;

// The deferred marches (module comment): appended by the dispatches without the band's
// lookups, marched by the one with CROSSING over them (an indirect dispatch, 64 to a
// workgroup; the same layout as right_eye.wgsl's list).
override CROSSING: bool = false;
struct DeferredMarches {
    groups_x: atomic<u32>,
    groups_y: u32,
    groups_z: u32,
    count: atomic<u32>,
    // Occlusion pixel p of layer z packed as p.x | p.y << 15 | z << 30.
    pixels: array<u32>,
};
@group(0) @binding(13) var<storage, read_write> deferred: DeferredMarches;

// Lists pixel `id`'s march for the CROSSING dispatch.
fn defer_march(id: vec3<u32>) {
    let i = atomicAdd(&deferred.count, 1u);
    deferred.pixels[i] = id.x | (id.y << 15u) | (id.z << 30u);
    if (i % 64u == 0u) {
        atomicAdd(&deferred.groups_x, 1u);
    }
}

// GTAO's own parameters (passes/gtao/mod.rs `GtaoUniform`).
struct GtaoParams {
    // Slices per pixel and depth samples along each half-slice (slices × 2 × steps ≈ N).
    slices: u32,
    steps: u32,
    // The slab behind each depth sample, as a fraction of the radius.
    thickness: f32,
    // Sample i of n along a half-slice lies at r · t ((2 − P) + (P − 1) t), with
    // t = (i + jitter) / n and P = step_power in 1..=2.
    step_power: f32,
    // Successive samples closer in distance than this fraction of the radius lie on one
    // continuous surface (0: never).
    connect: f32,
    // Columns along each eye's inner border marched with the other-eye lookups.
    inner_band: u32,
    // The share of its stratum a solid depth sample blocks on its own plane (`add_sample`).
    footprint: f32,
    // `right_eye_reuse`'s step: 0 lists, 1 copies (two uniform buffers, one pipeline).
    right_eye_step: u32,
};
@group(0) @binding(11) var<uniform> gtao: GtaoParams;

// The left eye's interior dispatch over its 8×8 tiles followed by the right eye's listed
// pixels, 64 to a workgroup, in one indirect dispatch (module comment).
override FOLDED: bool = false;

// The interior's tiles (the image less the inner band, 8×8 pixels each), x and y.
fn interior_tiles() -> vec2<u32> {
    let band = min(gtao.inner_band, ao.ao_size.x);
    return (vec2<u32>(ao.ao_size.x - band, ao.ao_size.y) + vec2<u32>(7u)) / 8u;
}

// The occlusion pixel of invocation `invocation` (in workgroup `group`, at `local` within
// it) in this dispatch's part of the image, or none (x = ao_size.x) past its part's width.
fn dispatch_pixel(invocation: vec3<u32>, group: vec3<u32>, local: u32) -> vec3<u32> {
    var id = invocation;
    if (FOLDED) {
        let tiles = interior_tiles();
        let left_tiles = tiles.x * tiles.y;
        if (group.x >= left_tiles) {
            return listed_right_pixel((group.x - left_tiles) * 64u + local);
        }
        let tile = vec2<u32>(group.x % tiles.x, group.x / tiles.x);
        id = vec3<u32>(tile * 8u + vec2<u32>(local % 8u, local / 8u), 0u);
    }
    if (CROSSING) {
        let i = group.x * 64u + local;
        if (i >= atomicLoad(&deferred.count)) {
            return vec3<u32>(ao.ao_size.x, 0u, 0u);
        }
        let packed = deferred.pixels[i];
        return vec3<u32>(packed & 0x7fffu, (packed >> 15u) & 0x7fffu, packed >> 30u);
    }
    if (RIGHT_EYE) {
        return right_eye_pixel(id, group, local);
    }
    let band = min(gtao.inner_band, ao.ao_size.x);
    let band_on_left = id.z < frame.layers && other_eye_side(frame.eyes[min(id.z, 1u)]) < 0.0;
    var x = ao.ao_size.x;
    if (INNER_BAND) {
        if (id.x < band) {
            x = select(ao.ao_size.x - band + id.x, id.x, band_on_left);
        }
    } else if (id.x < ao.ao_size.x - band) {
        x = select(id.x, id.x + band, band_on_left);
    }
    return vec3<u32>(x, id.y, id.z);
}

// The slice's frame and its hemisphere's cumulative weight.
struct Slice {
    // Unit vector in the slice plane, perpendicular to V, towards positive θ.
    t: vec3<f32>,
    // The receiver's normal, and 1 / the length of its projection into the slice.
    normal: vec3<f32>,
    inv_projected_len: f32,
    // The horizon directions of the tangent plane in the slice, at θ_max and θ_min.
    horizon_plus: vec3<f32>,
    horizon_minus: vec3<f32>,
    cos_gamma: f32,
    sin_gamma: f32,
    theta_min: f32,
    theta_max: f32,
    // G(θ_min), and 1 / total weight of the hemisphere in this slice.
    g_min: f32,
    inv_total: f32,
};

// acos on [−1, 1] to about 7e-5 rad (Abramowitz and Stegun 4.4.45): a square root and a
// cubic instead of the library's longer polynomial.
fn fast_acos(x: f32) -> f32 {
    let a = abs(x);
    let r = sqrt(max(1.0 - a, 0.0)) * (1.5707288 + a * (-0.2121144 + a * (0.0742610 - 0.0187293 * a)));
    return select(r, PI - r, x < 0.0);
}

fn fast_asin(x: f32) -> f32 {
    return 0.5 * PI - fast_acos(x);
}

// u(θ) of the direction from P along `d` (any length > 0) on half `side` of the slice:
// the cumulative cosine weight from θ_min, normalised; −1 when θ lies past V (θ = 0), on
// the other half. The angle comes from the direction's elevation e above the tangent
// plane (sin e = d̂·n / |n projected|, the sign of cos e from the half's horizon),
// θ = θ_max − e or θ_min + e: exact for a point in the slice plane, and a point of the
// tangent plane that the pixel grid puts a little off the slice still lies exactly on
// the horizon (its in-slice angle would not).
fn sector_coordinate(slice: Slice, d: vec3<f32>, side: f32) -> f32 {
    let inv_len = inverseSqrt(max(dot(d, d), 1e-30));
    let sin_e = dot(d, slice.normal) * inv_len * slice.inv_projected_len;
    if (!(sin_e > 0.0)) {
        // At or below the horizon.
        return select(0.0, 1.0, side > 0.0);
    }
    let x = min(sin_e, 1.0);
    let horizon = select(slice.horizon_minus, slice.horizon_plus, side > 0.0);
    let cos_e = select(-1.0, 1.0, dot(d, horizon) >= 0.0) * sqrt(max(1.0 - x * x, 0.0));
    let e = select(PI - fast_asin(x), fast_asin(x), cos_e >= 0.0);
    let theta = select(slice.theta_min + e, slice.theta_max - e, side > 0.0);
    if (theta * side < 0.0) {
        return -1.0;
    }
    // cos(2θ − γ) = −cos(γ ± 2e), with cos 2e and sin 2e from sin e and cos e.
    let cos_2e = 1.0 - 2.0 * x * x;
    let sin_2e = 2.0 * x * cos_e;
    let cos_2t_minus_g = -(slice.cos_gamma * cos_2e + side * slice.sin_gamma * sin_2e);
    // G(θ) = ¼ (−cos(2θ − γ) + cos γ + 2θ sin γ): the weight between 0 and θ.
    let g = 0.25 * (slice.cos_gamma - cos_2t_minus_g + 2.0 * theta * slice.sin_gamma);
    return clamp((slice.g_min + side * g) * slice.inv_total, 0.0, 1.0);
}

// The bits of the sectors [lo, hi] covers (u coordinates), its ends rounded with a
// per-pixel `offset` in [0, 1) rather than to the nearest: a slab narrower than a sector
// then sets its bit as often as its width says, over the noise tile, instead of never
// (nearest rounding dropped thin far occluders: a light bias).
fn sector_bits(lo: f32, hi: f32, offset: f32) -> u32 {
    let start = u32(clamp(floor(lo * SECTORS + offset), 0.0, SECTORS));
    let end = u32(clamp(floor(hi * SECTORS + offset), 0.0, SECTORS));
    if (end <= start) {
        return 0u;
    }
    let count = end - start;
    let ones = select((1u << count) - 1u, 0xffffffffu, count >= 32u);
    return ones << start;
}

// The slice's visible share in sectors (0..=32). Every interval a sample blocks lies on
// its own half, beyond the one nearest V on that half, so the gap between those two,
// around V, is open: exactly, and never empty while no slab reaches V itself (the eye
// sees the pixel, so the direction to it is clear). Rounded like the rest, that gap
// was counted as the whole sectors it crosses (`sector_bits` leaves the sectors from
// floor(a·32 + offset) up to floor(b·32 + offset) clear): as often none as one, when it
// is narrower than a sector. With a receiver seen through a narrow opening (a window
// behind a slatted blind), every slice's gap rounded away at once and AO read exactly
// 0 (black after tone mapping); more steps per slice (ultra) find fronts nearer V and
// narrow the gap further. The rounded count has the exact width as its mean over the
// per-pixel offsets, so counting the gap at its width instead keeps the mean.
fn visible_sectors(march: March, offset: f32) -> f32 {
    let a = clamp(march.near_minus, 0.0, 1.0);
    let b = clamp(march.near_plus, 0.0, 1.0);
    let clear = SECTORS - f32(countOneBits(march.occluded));
    if (!(b > a)) {
        return clear;
    }
    let rounded_gap = floor(b * SECTORS + offset) - floor(a * SECTORS + offset);
    return clear - rounded_gap + (b - a) * SECTORS;
}

// One slice's march so far: its occluded sectors, the previous sample of the current
// half (its sector coordinate, −1 when none, and its distance) for `connect`, and the
// ends of the occluded intervals nearest V on each half (`near_plus` the least u
// blocked on the + half, `near_minus` the greatest on the − half; 2 and −1 while none):
// the directions between them, around V, are exactly open (`visible_sectors`).
struct March {
    occluded: u32,
    previous_u: f32,
    previous_distance: f32,
    near_plus: f32,
    near_minus: f32,
};

struct SampleLimits {
    // Where sector boundaries round (`sector_bits`), per pixel.
    sector_offset: f32,
    radius2: f32,
    thickness: f32,
    connect: f32,
};

// Screen distance of step i of `steps` along a half-slice: spread by `step_power`
// (crowded near the pixel), jittered per pixel, and at least one pixel per step.
fn step_offset_px(i: u32, steps: u32, jitter: f32, march_px: f32) -> f32 {
    let t = (f32(i) + jitter) / f32(steps);
    // t ((2 − P) + (P − 1) t): between even (P = 1) and quadratic (P = 2); two
    // multiply-adds, where t^P cost a pow per sample and was no more accurate
    // (docs/records/2026-11-29/measurements-in-code.md, gtao-step-power).
    return max(t * mix(1.0, t, gtao.step_power - 1.0) * march_px, f32(i) + 1.0);
}

// A depth sample's plane and stratum: on a card (`THIN_CARDS`) or, for a solid sample
// with `FOOTPRINT`, its footprint; the surface's view-space normal, and the view
// rays (any length) that bound the share of the march the sample blocks on that plane
// (a card's whole stratum; a solid sample's `footprint` share of it, about the sample).
struct Card {
    on_card: bool,
    footprint: bool,
    normal: vec3<f32>,
    ray_a: vec3<f32>,
    ray_b: vec3<f32>,
};

// Whether the end of a card's footprint (relative to P) can be used: within r, in front
// of the eye; NaN and infinite ends (a ray along the card's plane) fail.
fn usable_card_end(end: vec3<f32>, p: vec3<f32>, radius2: f32) -> bool {
    return dot(end, end) < radius2 && end.z + p.z < 0.0;
}

// The ends of a card's footprint (its rays `ray_a`, `ray_b` met on the plane through
// `surface` with the card's normal), relative to P.
fn card_ends(card: Card, surface: vec3<f32>, p: vec3<f32>) -> array<vec3<f32>, 2> {
    let plane = dot(surface, card.normal);
    return array<vec3<f32>, 2>(
        card.ray_a * (plane / dot(card.ray_a, card.normal)) - p,
        card.ray_b * (plane / dot(card.ray_b, card.normal)) - p,
    );
}

// Marks the sectors that the depth sample `surface` (view space, w = 0 when none) blocks
// for the receiver at `p` on half `side` (+1 towards `t`, −1 away) of the slice: the
// slab from the visible surface back to `thickness` behind it (with `SECOND_LAYER` and
// w > 1, back to the second layer's surface at w × its distance along its view ray), joined to the previous
// sample when both lie on one continuous surface, and widened to its footprint on its
// plane (`card.footprint`: the footprint's ends that lie within r and in front of the
// eye; in expectation over the jitter a thin occluder then blocks its own width, where a
// point sample lands on it too rarely). A sample on a card has no depth behind
// it: it blocks its stratum's footprint on the card's plane instead, so where a stratum
// is part hole, part card, the holes' share of the samples blocks nothing and over the
// jittered strata the blocked angles average to the card's. Cards have no inside: no
// sample joins them. Either way two directions bound what is blocked, so solid and card
// samples share one path (a SIMD group marching over both pays each once).
fn add_sample(
    march: ptr<function, March>, slice: Slice, side: f32, p: vec3<f32>, surface: vec4<f32>, card: Card,
    limits: SampleLimits,
) {
    if (surface.w == 0.0) {
        (*march).previous_u = -1.0;
        return;
    }
    let front = surface.xyz - p;
    let front2 = dot(front, front);
    let sample_distance = -surface.z;
    let on_card = THIN_CARDS && card.on_card;
    if (!(front2 < limits.radius2)) {
        (*march).previous_u = -1.0;
        (*march).previous_distance = sample_distance;
        return;
    }
    // The two bounding directions: the front and the slab's back, or the footprint's
    // ends on the card's plane (the sample itself where an end is not usable).
    var end_a = front;
    var end_b: vec3<f32>;
    if (on_card) {
        let ends = card_ends(card, surface.xyz, p);
        let a = ends[0];
        let b = ends[1];
        end_a = select(front, a, usable_card_end(a, p, limits.radius2));
        end_b = select(front, b, usable_card_end(b, p, limits.radius2));
    } else {
        // The slab's back along the sample's view ray, clipped where it leaves the
        // sphere of radius r about P. The slab sweeps from its front away from V (its
        // line passes through the eye, never through V): a back below the tangent plane
        // reads as this half's horizon, one past V (by rounding) stops at V.
        let ray = normalize(surface.xyz);
        let along = dot(front, ray);
        let to_sphere = -along + sqrt(max(along * along - front2 + limits.radius2, 0.0));
        var slab = limits.thickness;
        if (SECOND_LAYER && surface.w > 1.0) {
            // The span to the second layer: (w − 1) × the sample's distance from the eye.
            slab = length(surface.xyz) * (surface.w - 1.0);
        }
        end_b = front + ray * min(slab, to_sphere);
    }
    // A front past V belongs to the other half: the pixel grid put the sample off the
    // slice, across the view plane (a short step from an off-centre pixel), typically
    // in the tangent plane. It occludes nothing here; mapped onto this half, with its
    // back at this half's horizon, it blocked the whole half (isolated dark pixels on an
    // open plane). A card's footprint may reach V (its stratum starts at the pixel): it
    // stops there.
    let u_a_raw = sector_coordinate(slice, end_a, side);
    if (u_a_raw < 0.0 && !on_card) {
        (*march).previous_u = -1.0;
        (*march).previous_distance = sample_distance;
        return;
    }
    let u_b_raw = sector_coordinate(slice, end_b, side);
    let u_v = slice.g_min * slice.inv_total;
    let u_a = select(u_a_raw, u_v, u_a_raw < 0.0);
    let u_b = select(u_b_raw, u_v, u_b_raw < 0.0);
    var lo = min(u_a, u_b);
    var hi = max(u_a, u_b);
    if (FOOTPRINT && card.footprint) {
        let ends = card_ends(card, surface.xyz, p);
        let a = ends[0];
        let b = ends[1];
        if (usable_card_end(a, p, limits.radius2)) {
            let raw = sector_coordinate(slice, a, side);
            let ua = select(raw, u_v, raw < 0.0);
            lo = min(lo, ua);
            hi = max(hi, ua);
        }
        if (usable_card_end(b, p, limits.radius2)) {
            let raw = sector_coordinate(slice, b, side);
            let ub = select(raw, u_v, raw < 0.0);
            lo = min(lo, ub);
            hi = max(hi, ub);
        }
    }
    if (on_card) {
        (*march).previous_u = -1.0;
        if (u_a_raw >= 0.0 || u_b_raw >= 0.0) {
            block(march, side, lo, hi, limits.sector_offset);
        }
        return;
    }
    if ((*march).previous_u >= 0.0 && abs(sample_distance - (*march).previous_distance) < limits.connect) {
        lo = min(lo, (*march).previous_u);
        hi = max(hi, (*march).previous_u);
    }
    block(march, side, lo, hi, limits.sector_offset);
    (*march).previous_u = u_a;
    (*march).previous_distance = sample_distance;
}

// Sets the sectors [lo, hi] on half `side` and keeps the blocked end nearest V.
fn block(march: ptr<function, March>, side: f32, lo: f32, hi: f32, sector_offset: f32) {
    (*march).occluded |= sector_bits(lo, hi, sector_offset);
    if (side > 0.0) {
        (*march).near_plus = min((*march).near_plus, lo);
    } else {
        (*march).near_minus = max((*march).near_minus, hi);
    }
}

@compute @workgroup_size(8, 8, 1)
fn main(
    @builtin(global_invocation_id) invocation: vec3<u32>,
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let id = dispatch_pixel(invocation, group, local);
    let r = begin_receiver(id);
    if (!r.valid) {
        return;
    }
    // The first right-eye dispatch stored what the left eye gives; these march.
    let p = r.position;
    let view = normalize(-p);
    let distance = -p.z;
    // Tangent span of one full-res pixel along x and y (y grows downwards on screen).
    let pixel_tangent = vec2<f32>(r.eye.tangents.y - r.eye.tangents.x, r.eye.tangents.w - r.eye.tangents.z)
        / vec2<f32>(frame.size);
    let radius = ao.radius;
    let radius_px = radius / max(abs(pixel_tangent.x) * distance, 1e-30);
    if (!(radius_px >= 1.0)) {
        // The whole radius lies inside this pixel: nothing to find.
        store_occlusion(id, vec4<f32>(open_light(r), 1.0));
        return;
    }
    // Never march further than the image's diagonal.
    let march_px = min(radius_px, f32(frame.size.x + frame.size.y));
    var limits: SampleLimits;
    limits.radius2 = radius * radius;
    limits.thickness = gtao.thickness * radius;
    limits.connect = gtao.connect * radius;
    let size = vec2<f32>(frame.size);
    let centre_px = vec2<f32>(r.pixel) + vec2<f32>(0.5);
    // Fewer slices, then steps, towards the image's edges with fixed foveation
    // (occlusion.wgsl).
    let counts = foveated_march(max(gtao.slices, 1u), max(gtao.steps, 1u), foveation_rate(id.xy, r.layer), id.xy);
    let slices = counts.x;
    let steps = counts.y;
    // Whether any step can leave the image through the inner border, the only one the
    // other eye sees past (steps are at least a pixel apart, so the march reaches at most
    // max(march_px, steps) pixels out).
    let reach_px = max(march_px, f32(steps));
    let inner = other_eye_side(r.eye);
    let crosses = (inner > 0.0 && centre_px.x + reach_px >= size.x) || (inner < 0.0 && centre_px.x - reach_px < 0.0);
    if (crosses && !INNER_BAND) {
        defer_march(id);
        return;
    }
    let near_inner_border = INNER_BAND && crosses;
    // The tile is laid over occlusion pixels (at half resolution the full-res pixel has
    // even coordinates only, which would leave 4 of the 16 patterns).
    let rotation_noise = bayer4(stereo_noise_pixel(id.xy, ao.ao_size, r.layer, r.eye, p));
    // A second, decorrelated value of the same tile for the step jitter.
    let jitter = fract(rotation_noise * 7.0 + 0.3125);
    // A third value of the same tile (11 is prime to 16: all 16 values occur).
    limits.sector_offset = fract(rotation_noise * 11.0 + 0.71875);
    var visible = 0.0;
    var total = 0.0;
    // What a light-gathering march (SSDO, passes/ssdo) adds up besides the visibility;
    // nothing for GTAO (gtao_light.wgsl).
    var light = begin_light(rotation_noise);
    // Slice directions: the pixel's first, then turned by π / slices each (one sin/cos
    // pair per pixel and one per frame instead of one per slice).
    let phi0 = rotation_noise * PI / f32(slices) + ao.frame_angle;
    var omega = vec2<f32>(cos(phi0), sin(phi0));
    let turn = vec2<f32>(cos(PI / f32(slices)), sin(PI / f32(slices)));
    for (var s = 0u; s < slices; s++) {
        if (s > 0u) {
            omega = vec2<f32>(omega.x * turn.x - omega.y * turn.y, omega.x * turn.y + omega.y * turn.x);
        }
        let direction = normalize(vec3<f32>(omega * pixel_tangent, 0.0));
        var slice: Slice;
        slice.t = normalize(direction - dot(direction, view) * view);
        let axis = cross(slice.t, view);
        let projected = r.normal - axis * dot(r.normal, axis);
        let projected_len = length(projected);
        if (!(projected_len > 1e-6)) {
            continue;
        }
        slice.cos_gamma = clamp(dot(projected, view) / projected_len, -1.0, 1.0);
        slice.sin_gamma = dot(projected, slice.t) / projected_len;
        // The normal faces the eye (occlusion.wgsl `repaired_normal`): cos γ > 0, |γ| < π/2.
        let gamma = select(-1.0, 1.0, slice.sin_gamma >= 0.0) * fast_acos(slice.cos_gamma);
        slice.theta_min = gamma - 0.5 * PI;
        slice.theta_max = gamma + 0.5 * PI;
        slice.g_min = 0.5 * (slice.cos_gamma + slice.theta_min * slice.sin_gamma);
        let slice_total = slice.cos_gamma + gamma * slice.sin_gamma;
        if (!(slice_total > 1e-6)) {
            continue;
        }
        slice.inv_total = 1.0 / slice_total;
        slice.normal = r.normal;
        slice.inv_projected_len = 1.0 / projected_len;
        slice.horizon_plus = slice.cos_gamma * slice.t - slice.sin_gamma * view;
        slice.horizon_minus = -slice.horizon_plus;
        var march: March;
        march.occluded = 0u;
        march.near_plus = 2.0;
        march.near_minus = -1.0;
        for (var half = 0u; half < 2u; half++) {
            let sign = select(-1.0, 1.0, half == 0u);
            march.previous_u = -1.0;
            march.previous_distance = distance;
            // A straight march from inside the image never comes back once it leaves:
            // the steps on the image read this eye's depth directly, and only those
            // past the inner border (few pixels, near it) ask the other eye. Past the
            // outer, top and bottom borders the other eye sees no further: open.
            var i = 0u;
            for (; i < steps; i++) {
                let q = centre_px + sign * omega * step_offset_px(i, steps, jitter, march_px);
                if (any(q < vec2<f32>(0.0)) || any(q >= size)) {
                    break;
                }
                let pixel = vec2<u32>(q);
                let d = textureLoad(depth_layers, vec2<i32>(pixel), i32(r.layer), 0);
                let surface = load_view_position(d, pixel, r.eye, frame.size, frame.near);
                var card: Card;
                card.on_card = false;
                card.footprint = false;
                // Only a sample within r and above the tangent plane can block: the
                // others skip the normal's fetch.
                let to_sample = surface - p;
                if ((THIN_CARDS || FOOTPRINT) && d > 0.0 && dot(to_sample, to_sample) < limits.radius2 && dot(to_sample, r.normal) > 0.0) {
                    let n = textureLoad(normal_layers, vec2<i32>(pixel), i32(r.layer), 0);
                    card.on_card = THIN_CARDS && n.w > 0.5;
                    card.footprint = FOOTPRINT && !card.on_card;
                    if (card.on_card || card.footprint) {
                        card.normal = n.xyz;
                        // The stratum's ends: where the step would lie with jitter 0 and 1,
                        // widened to a pixel about its middle where it is narrower (steps
                        // a pixel apart, near the pixel or with more steps than the radius
                        // has pixels, have no jitter left and would block no width).
                        let first = step_offset_px(i, steps, 0.0, march_px);
                        let last = step_offset_px(i, steps, 1.0, march_px);
                        let widen = 0.5 * max(1.0 - (last - first), 0.0);
                        var qa = centre_px + sign * omega * (first - widen);
                        var qb = centre_px + sign * omega * (last + widen);
                        if (card.footprint) {
                            qa = mix(q, qa, gtao.footprint);
                            qb = mix(q, qb, gtao.footprint);
                        }
                        card.ray_a = view_position_from_distance(qa / size, 1.0, r.eye.tangents);
                        card.ray_b = view_position_from_distance(qb / size, 1.0, r.eye.tangents);
                    }
                }
                // w: 0 on the sky, 1 for a surface of unknown thickness, and with a second
                // layer behind it the ratio of its distance to the first's (d / d₂ in
                // reversed Z), > 1.
                var sample = select(vec4<f32>(0.0), vec4<f32>(surface, 1.0), d > 0.0);
                if (SECOND_LAYER && d > 0.0) {
                    let d2 = textureLoad(second_depth_layers, vec2<i32>(pixel), i32(r.layer), 0);
                    // A front face behind the sample: the sample is on a sheet, whose
                    // span to the next object is air; the thickness stands instead.
                    if (d2 > 0.0 && d2 < d && !second_layer_faces_eye(d2)) {
                        sample.w = d / d2;
                    }
                }
                let covered = march.occluded;
                add_sample(&march, slice, sign, p, sample, card, limits);
                gather_sample(&light, march.occluded & ~covered, pixel, r.layer, surface, p);
            }
            let towards_inner = near_inner_border && sign * omega.x * inner > 0.0;
            for (; towards_inner && i < steps; i++) {
                let q = centre_px + sign * omega * step_offset_px(i, steps, jitter, march_px);
                if (q.y < 0.0 || q.y >= size.y) {
                    break;
                }
                // The other eye's samples count as solid: only its depth is looked up.
                var solid: Card;
                solid.on_card = false;
                solid.footprint = false;
                add_sample(&march, slice, sign, p, surface_at(q, r.layer, r.eye, march.previous_distance), solid, limits);
            }
        }
        let weight = projected_len * slice_total;
        visible += weight * visible_sectors(march, limits.sector_offset) / SECTORS;
        total += weight;
        end_slice(&light, slice, march, limits.sector_offset, projected_len, weight, view);
    }
    var visibility = 1.0;
    if (total > 1e-12) {
        visibility = visible / total;
    }
    let result = saturate_ao(1.0 - ao.strength * (1.0 - visibility));
    store_occlusion(id, vec4<f32>(light_result(light, r, visibility, total), result));
}

// GTAO's right eye around its folded dispatch, one pipeline for both steps so that both
// make the same test on the same inputs with the same code (a pixel listed and copied,
// or neither, would be a stale value): before it (`right_eye_step` 0) the pixels the left
// eye cannot give are listed (`left_eye_value_from_depth`), and the list's dispatch
// argument first counts the left eye's interior tiles; after it (1) every pixel's
// geometry (and the sky) is written, and the left eye's value wherever the pixel was not
// listed.
@compute @workgroup_size(8, 8, 1)
fn right_eye_reuse(@builtin(global_invocation_id) invocation: vec3<u32>) {
    let id = vec3<u32>(invocation.xy, 1u);
    let copy = gtao.right_eye_step == 1u;
    if (!copy && all(invocation.xy == vec2<u32>(0u))) {
        let tiles = interior_tiles();
        atomicAdd(&right_list.groups_x, tiles.x * tiles.y);
    }
    // One call site each for the point and the test, whichever the step: the same code.
    var r = receiver_point(id);
    if (copy) {
        r = with_normal(r);
        store_receiver(id, r);
    }
    if (!r.valid) {
        return;
    }
    let left = left_eye_value_from_depth(r.position);
    if (!left.found) {
        if (!copy) {
            list_right_pixel(id);
        }
    } else if (copy) {
        let value = chain_gather_blend(left_occlusion, gather, left.corner, 0, left.weights);
        store_occlusion(id, vec4<f32>(reused_light(value), value.a));
    }
}
