// Linear radiance to display sRGB: x / (1 + x) with x = exposure L per channel (Reinhard et al.
// 2002, the global operator), then the sRGB curve.
// Must match image_tonemap() in src/render/image.c.

#include "bindings.h"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = BIND_TONEMAP_IMG_IN) uniform readonly image2D in_image;
layout(rgba8, binding = BIND_TONEMAP_IMG_OUT) uniform writeonly image2D out_image;
uniform float exposure;
uniform ivec2 image_size;

float srgb(float c)
{
    return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

void main()
{
    ivec2 pix = ivec2(gl_GlobalInvocationID.xy);
    if (pix.x >= image_size.x || pix.y >= image_size.y)
        return;
    vec3 l = imageLoad(in_image, pix).rgb;
    vec3 x = exposure * max(l, vec3(0.0));
    vec3 c = x / (1.0 + x);
    imageStore(out_image, pix, vec4(srgb(c.r), srgb(c.g), srgb(c.b), 1.0));
}
