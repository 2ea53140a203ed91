// Environment light for the passes that bind `frame` (SSDO, composite): the irradiance
// SH9 and the pre-filtered radiance (its first two bands) are polynomials in the direction,
// stored per eye in its view space (`frame.environment_quadratics`), so a view-space
// normal or a sum of view-space directions needs no turn into the world.

const IRRADIANCE: u32 = 0u;
const RADIANCE: u32 = 2u;

// Σ_i c_i f(ω_i) for the quadratic f of `frame.environment_quadratics` that starts at
// `first` (IRRADIANCE or RADIANCE), in eye `layer`, from the moments m0 = Σc, m1 = Σcω and
// Σcωωᵀ (diagonal, and off-diagonal as xy, xz, yz). Reads the uniform in place: with
// the array copied by value into a local, SSDO ran slower on lavapipe
// (docs/records/2026-11-29/measurements-in-code.md, irradiance-in-place).
fn quadratic_sum(first: u32, layer: u32, m0: f32, m1: vec3<f32>, diag: vec3<f32>, off: vec3<f32>) -> vec3<f32> {
    let q = &frame.environment_quadratics[first + layer];
    return q[0].xyz * m0 + q[1].xyz * m1.x + q[2].xyz * m1.y + q[3].xyz * m1.z
        + q[4].xyz * diag.x + q[5].xyz * diag.y + q[6].xyz * diag.z
        + q[7].xyz * off.x + q[8].xyz * off.y + q[9].xyz * off.z;
}

// Σ_i c_i f(ω_i) for a quadratic f whose second-order rows vanish (the pre-filtered
// radiance, `Environment::radiance_sh_prefiltered`): m0 = Σc and m1 = Σcω are enough.
fn linear_sum(first: u32, layer: u32, m0: f32, m1: vec3<f32>) -> vec3<f32> {
    let q = &frame.environment_quadratics[first + layer];
    return q[0].xyz * m0 + q[1].xyz * m1.x + q[2].xyz * m1.y + q[3].xyz * m1.z;
}

// The irradiance E(n) on a surface of view-space unit normal `n` in eye `layer` that sees
// the whole environment (Ramamoorthi & Hanrahan 2001). Clamped at 0 because nine
// coefficients can ring negative opposite a bright sun.
fn environment_irradiance(layer: u32, n: vec3<f32>) -> vec3<f32> {
    let off = vec3<f32>(n.x * n.y, n.x * n.z, n.y * n.z);
    return max(quadratic_sum(IRRADIANCE, layer, 1.0, n, n * n, off), vec3<f32>(0.0));
}
