// The device's peak rate of trilinear 3D texture fetches, for anvil bench --gpu: every
// invocation takes FETCHES filtered samples of a small RG32F volume (it stays in the texture
// cache) at points that drift smoothly, as an eye ray's do, and sums them so that none is
// optimised away.  The rate it reaches is what the eye pass's fetches are measured against.

#include "bindings.h"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = BIND_PEAK_TEX_VOLUME) uniform sampler3D volume;
layout(r32f, binding = BIND_PEAK_IMG_OUT) uniform writeonly image2D out_image;

uniform ivec2 size;
uniform int fetches;

void main()
{
    ivec2 pix = ivec2(gl_GlobalInvocationID.xy);
    if (pix.x >= size.x || pix.y >= size.y)
        return;
    vec3 p = vec3(vec2(pix) / vec2(size), 0.0);
    vec3 d = normalize(vec3(0.3, 0.2, 1.0)) / float(fetches);
    float sum = 0.0;
    for (int i = 0; i < fetches; i++) {
        vec2 v = texture(volume, p).rg;
        sum += v.x + v.y;
        p += d;
    }
    imageStore(out_image, pix, vec4(sum));
}
