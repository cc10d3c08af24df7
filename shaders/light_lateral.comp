// Deep light map, multiple scattering with lateral escape: each voxel's extinction times its
// lateral escape rate along one horizontal axis, one invocation per row of the volume
// (docs/lightmap.md, "Lateral escape").  The rate is 1 / w, w the optical width of the run of
// cloudy voxels that holds the voxel; clear voxels get 0.  Mirrors light_lateral_rates() in
// src/light/transport.c operation for operation in float32: the pass along x writes .r (and
// clears .g), the pass along y then writes .g beside it.

#include "bindings.h"

layout(local_size_x = 64) in;

layout(binding = BIND_LATERAL_TEX_BETA) uniform sampler3D beta_tex;       // texelFetch only
layout(rg32f, binding = BIND_LATERAL_IMG_RATES) uniform image3D rates_img; // beta / w: x, y

uniform ivec3 vol_n;
uniform int axis;         // 0: rows along x, 1: rows along y
uniform float spacing;    // metres between voxels along the axis
uniform float clear_beta; // LIGHT_CLEAR_BETA

ivec3 voxel(int i, int r, int k)
{
    return axis == 0 ? ivec3(i, r, k) : ivec3(r, i, k);
}

float beta_at(ivec3 c)
{
    vec2 b = texelFetch(beta_tex, c, 0).rg;
    return b.x + b.y;
}

// Two sweeps of the row, the same length for every invocation: forward, each cloudy voxel
// keeps the optical width of its run so far (in the axis' own channel); backward, the run's
// last voxel holds the whole width, which every voxel of the run then divides its
// extinction by.
void main()
{
    int len = vol_n[axis], rows = vol_n[1 - axis];
    int id = int(gl_GlobalInvocationID.x);
    if (id >= rows * vol_n.z)
        return;
    int r = id % rows, k = id / rows;
    float w = 0.0;
    for (int i = 0; i < len; i++) {
        ivec3 c = voxel(i, r, k);
        float b = beta_at(c);
        w = b >= clear_beta ? w + min(b, 1e30) * spacing : 0.0; // 0 also for NaN
        if (axis == 0)
            imageStore(rates_img, c, vec4(w, 0.0, 0.0, 0.0));
        else
            imageStore(rates_img, c, vec4(imageLoad(rates_img, c).r, w, 0.0, 0.0));
    }
    float total = 0.0;
    for (int i = len - 1; i >= 0; i--) {
        ivec3 c = voxel(i, r, k);
        vec2 v = imageLoad(rates_img, c).rg;
        float here = axis == 0 ? v.x : v.y;
        // A run's last voxel (cloudy, and the next one is not) holds the run's width.
        total = here > 0.0 ? (total > 0.0 ? total : here) : 0.0;
        float rate = here > 0.0 ? min(beta_at(c), 1e30) / total : 0.0;
        if (axis == 0)
            imageStore(rates_img, c, vec4(rate, 0.0, 0.0, 0.0));
        else
            imageStore(rates_img, c, vec4(v.x, rate, 0.0, 0.0));
    }
}
