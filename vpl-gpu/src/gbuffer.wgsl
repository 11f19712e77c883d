// The G-buffer: one camera ray through each pixel centre, twin of
// vpl_shading::render_gbuffer. Outputs, one vec4 a pixel each:
//   g_pos     [p, 1 where the point reflects light toward the camera, else 0]
//   g_normal  [shading normal toward the camera, depth (NO_HIT for a miss)]
//   g_ng      [geometric normal toward the camera, material (bit-cast)]
//   g_albedo  [albedo (zero seen from behind a one-sided surface), 0]
//   g_emitted [radiance emitted toward the camera, 0]

struct Camera {
    origin: vec4<f32>,
    // xyz and, in w: s_x (forward), s_y (right), focus distance (up; 0 for a pinhole).
    forward: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    width: u32,
    height: u32,
    two_sided: u32,
    // 1 where the scene has an environment (the sky below), else 0.
    has_sky: u32,
    // The environment's radiance at the zenith, the horizon and the nadir.
    sky_zenith: vec4<f32>,
    sky_horizon: vec4<f32>,
    sky_nadir: vec4<f32>,
}

@group(1) @binding(0) var<uniform> cam: Camera;
@group(1) @binding(1) var<storage, read_write> g_pos: array<vec4<f32>>;
@group(1) @binding(2) var<storage, read_write> g_normal: array<vec4<f32>>;
@group(1) @binding(3) var<storage, read_write> g_ng: array<vec4<f32>>;
@group(1) @binding(4) var<storage, read_write> g_albedo: array<vec4<f32>>;
@group(1) @binding(5) var<storage, read_write> g_emitted: array<vec4<f32>>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= cam.width || id.y >= cam.height) { return; }
    let i = id.y * cam.width + id.x;
    let ndc_x = 2.0 * (f32(id.x) + 0.5) / f32(cam.width) - 1.0;
    let ndc_y = 1.0 - 2.0 * (f32(id.y) + 0.5) / f32(cam.height);
    let o = cam.origin.xyz;
    var d = cam.forward.xyz + cam.right.xyz * (ndc_x * cam.forward.w) + cam.up.xyz * (ndc_y * cam.right.w);
    if (cam.up.w > 0.0) {
        // A thin lens sampled at its centre: toward the point in focus.
        d = (o + d * cam.up.w) - o;
    }
    d = normalize(d);
    let h = closest_hit(o, d, NO_HIT);
    if (h.prim == NONE) {
        g_pos[i] = vec4<f32>(0.0);
        g_normal[i] = vec4<f32>(0.0, 0.0, 1.0, NO_HIT);
        g_ng[i] = vec4<f32>(0.0, 0.0, 1.0, bitcast<f32>(NONE));
        g_albedo[i] = vec4<f32>(0.0);
        // The environment seen along the ray (Sky::radiance), as the host's
        // environment_at_misses fills it in.
        var sky = vec3<f32>(0.0);
        if (cam.has_sky != 0u) {
            let y = clamp(d.y, -1.0, 1.0);
            let hor = cam.sky_horizon.xyz;
            if (y >= 0.0) {
                sky = hor + (cam.sky_zenith.xyz - hor) * y;
            } else {
                sky = hor + (cam.sky_nadir.xyz - hor) * (-y);
            }
        }
        g_emitted[i] = vec4<f32>(sky, 0.0);
        return;
    }
    let p = o + d * h.t;
    let sf = surface_at(h.prim, p);
    let material = sf.material;
    var n = sf.n;
    var ng = sf.ng;
    let wo = -d;
    let front = dot(wo, ng) > 0.0;
    let albedo = materials[2u * material].xyz;
    var emitted = vec3<f32>(0.0);
    if (front) { emitted = materials[2u * material + 1u].xyz; }
    if (dot(wo, ng) < 0.0) {
        ng = -ng;
        n = -n;
    }
    var rho = vec3<f32>(0.0);
    if (front || cam.two_sided != 0u) { rho = albedo; }
    let reflects = max(max(rho.x, rho.y), rho.z) > 0.0;
    g_pos[i] = vec4<f32>(p, select(0.0, 1.0, reflects));
    g_normal[i] = vec4<f32>(n, h.t);
    g_ng[i] = vec4<f32>(ng, bitcast<f32>(material));
    g_albedo[i] = vec4<f32>(rho, 0.0);
    g_emitted[i] = vec4<f32>(emitted, 0.0);
}
