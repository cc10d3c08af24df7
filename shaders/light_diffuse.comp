// Deep light map, multiple scattering: the two-stream pass along every light column, one
// invocation per column, after light_build.comp has swept the beam (docs/lightmap.md,
// "Multiple scattering"): each column is solved as a plane-parallel atmosphere lit at mu0
// (the tilted independent column approximation).  Mirrors light_diffuse_column() in
// src/light/transport.c operation for operation in float32.  Variant: PHASE_MIX 0 when both
// phases' terms are equal (the ice share is then not read).

#ifndef PHASE_MIX
#define PHASE_MIX 1
#endif

layout(local_size_x = 8, local_size_y = 8) in;

layout(r32f, binding = 0) uniform readonly image3D light_img;   // the beam at each node
layout(rg32f, binding = 1) uniform readonly image3D slice_img;  // slice k-1..k: tau, ice share
layout(rg32f, binding = 2) uniform image3D adding_img;          // z = 1 / (1 - A), g
layout(rg32f, binding = 3) uniform writeonly image3D diffuse_img; // 2 (U + V), 2 (U - V)

uniform ivec3 grid_n;
uniform vec2 loss;  // the beam's loss share: water, ice
uniform vec2 back;  // lost and heading up toward the sun's side: water, ice
uniform vec2 gamma; // Eddington coupling 3 (1 - g) / 4: water, ice
uniform float mu0;  // |sin(elevation)|, at least 1e-3

struct slice_terms {
    float tau, loss, back, gamma;
};

slice_terms terms(ivec3 c)
{
    vec2 sl = imageLoad(slice_img, c).rg;
#if PHASE_MIX
    float fi = sl.y;
#else
    float fi = 0.0;
#endif
    slice_terms t;
    t.tau = min(sl.x, 1e8);
    t.loss = loss.x + fi * (loss.y - loss.x);
    float bk = back.x + fi * (back.y - back.x);
    t.back = min(max(bk / t.loss, 0.0), 1.0);
    t.gamma = gamma.x + fi * (gamma.y - gamma.x);
    return t;
}

// Diffuse light out of a slice's sun side (x) and far side (y), times (1 + gamma mu0 tau), for
// the beam D0 entering it (transport.c, column_slice and slice_sources).
vec2 sources(float d0, slice_terms t)
{
    float x = min(t.loss * t.tau, 1e8);
    float w = mu0 * d0 * (1.0 - exp(-x));
    float a1 = x < 0.1 ? 0.5 + x * (1.0 / 12.0) - x * x * x * (1.0 / 720.0)
                       : 1.0 / (1.0 - exp(-x)) - 1.0 / x;
    float gw = t.gamma * (mu0 * t.tau) * w;
    return vec2(t.back * w + gw * a1, (1.0 - t.back) * w + gw * (1.0 - a1));
}

void main()
{
    ivec2 ij = ivec2(gl_GlobalInvocationID.xy);
    if (ij.x >= grid_n.x || ij.y >= grid_n.y)
        return;
    int n = grid_n.z;
    float z = 1.0, g = 0.0; // beyond the last node: nothing sends light back
    imageStore(adding_img, ivec3(ij, n - 1), vec4(z, g, 0.0, 0.0));
    for (int l = n - 1; l >= 1; l--) {
        slice_terms t = terms(ivec3(ij, l));
        float gt = t.gamma * mu0 * t.tau;
        vec2 s = sources(imageLoad(light_img, ivec3(ij, l - 1)).r, t);
        float zt = z + gt;
        float a = 1.0 - 1.0 / z;
        g = s.x / (1.0 + gt) + (g + a * s.y / (1.0 + gt)) * (z / zt);
        z = zt;
        imageStore(adding_img, ivec3(ij, l - 1), vec4(z, g, 0.0, 0.0));
    }
    float u = 0.0; // no diffuse light enters from the sun's side
    imageStore(diffuse_img, ivec3(ij, 0), vec4(2.0 * g, -2.0 * g, 0.0, 0.0));
    float z_prev = z;
    for (int l = 1; l < n; l++) {
        slice_terms t = terms(ivec3(ij, l));
        float gt = t.gamma * mu0 * t.tau;
        vec2 s = sources(imageLoad(light_img, ivec3(ij, l - 1)).r, t);
        vec2 zg = imageLoad(adding_img, ivec3(ij, l)).rg;
        u = (u + gt * zg.y + s.y) * (zg.x / z_prev);
        float v = (1.0 - 1.0 / zg.x) * u + zg.y;
        imageStore(diffuse_img, ivec3(ij, l), vec4(2.0 * (u + v), 2.0 * (u - v), 0.0, 0.0));
        z_prev = zg.x;
    }
}
