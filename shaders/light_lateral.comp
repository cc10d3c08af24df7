// Deep light map, multiple scattering with lateral escape: each voxel's extinction times its
// lateral escape rate along one horizontal axis, one invocation per row of the volume
// (docs/lightmap.md, "Lateral escape").  The rate is 1 / w, w the optical width of the run of
// cloudy voxels that holds the voxel; clear voxels get 0.  Mirrors light_lateral_rates() in
// src/light/transport.c operation for operation in float32: the pass along x writes .r (and
// clears .g), the pass along y then writes .g beside it.

layout(local_size_x = 64) in;

layout(binding = 0) uniform sampler3D beta_tex;       // read with texelFetch only
layout(rg32f, binding = 0) uniform image3D rates_img; // beta / w along x, along y

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

void put(ivec3 c, float v)
{
    if (axis == 0) {
        imageStore(rates_img, c, vec4(v, 0.0, 0.0, 0.0));
    } else {
        float rx = imageLoad(rates_img, c).r;
        imageStore(rates_img, c, vec4(rx, v, 0.0, 0.0));
    }
}

void main()
{
    int len = vol_n[axis], rows = vol_n[1 - axis];
    int id = int(gl_GlobalInvocationID.x);
    if (id >= rows * vol_n.z)
        return;
    int r = id % rows, k = id / rows;
    int i = 0;
    while (i < len) {
        if (!(beta_at(voxel(i, r, k)) >= clear_beta)) { // clear, or NaN
            put(voxel(i, r, k), 0.0);
            i++;
            continue;
        }
        float w = 0.0;
        int end = i;
        for (; end < len; end++) {
            float be = beta_at(voxel(end, r, k));
            if (!(be >= clear_beta))
                break;
            w += min(be, 1e30) * spacing;
        }
        for (int m = i; m < end; m++)
            put(voxel(m, r, k), min(beta_at(voxel(m, r, k)), 1e30) / w);
        i = end;
    }
}
