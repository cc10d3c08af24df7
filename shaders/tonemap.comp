// Linear radiance to display sRGB: x / (1 + x) with x = exposure L per channel (Reinhard et al.
// 2002, the global operator), then the sRGB curve; negative and non-finite radiance read as 0
// (infinite exposure times radiance as white).  Must match image_tonemap() in
// src/render/image.c.  PACKED 1: the 8-bit values for a file, image_tonemap's to the bit: not
// computed here (a GPU's pow may round its last bit either way, and a value near a step then
// lands on the other side of it) but, as image_tonemap does, counted as the steps at or below
// x = exposure L (image_tonemap_steps, made on the CPU), packed into one uint per pixel
// (r | g << 8 | b << 16 | 255 << 24), and the pixels with a non-finite value counted; else an
// RGBA8 image to show.

#include "bindings.h"

#ifndef PACKED
#define PACKED 0
#endif

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = BIND_TONEMAP_IMG_IN) uniform readonly image2D in_image;
#if PACKED
layout(r32ui, binding = BIND_TONEMAP_IMG_OUT) uniform writeonly uimage2D out_image;
layout(std430, binding = BIND_TONEMAP_BUF_NONFINITE) buffer nonfinite_count {
    uint nonfinite;
};
#else
layout(rgba8, binding = BIND_TONEMAP_IMG_OUT) uniform writeonly image2D out_image;
#endif
uniform float exposure;
uniform ivec2 image_size;
#if PACKED
uniform float steps[255]; // IMAGE_TONEMAP_STEPS, ascending

// image_tonemap(L, exposure): how many steps lie at or below exposure L, by bisection.
uint quantize(float l)
{
    l = l > 0.0 && !isinf(l) ? l : 0.0; // NaN fails l > 0
    float x = exposure * l;              // one product, rounded as the CPU's
    uint v = 0u;
    for (uint half_width = 128u; half_width > 0u; half_width >>= 1) {
        uint k = v + half_width;
        if (k <= 255u && x >= steps[k - 1u])
            v = k;
    }
    return v;
}
#endif

float srgb(float c)
{
    return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

float tone(float l)
{
    l = l > 0.0 && !isinf(l) ? l : 0.0; // NaN fails l > 0
    float x = exposure * l;
    return srgb(isinf(x) ? 1.0 : x / (1.0 + x));
}

void main()
{
    ivec2 pix = ivec2(gl_GlobalInvocationID.xy);
    if (pix.x >= image_size.x || pix.y >= image_size.y)
        return;
    vec4 v = imageLoad(in_image, pix);
#if PACKED
    uvec3 q = uvec3(quantize(v.r), quantize(v.g), quantize(v.b));
    imageStore(out_image, pix, uvec4(q.r | (q.g << 8) | (q.b << 16) | (255u << 24)));
    if (any(isnan(v.rgb)) || any(isinf(v.rgb))) // as image_count_nonfinite
        atomicAdd(nonfinite, 1u);
#else
    vec3 c = vec3(tone(v.r), tone(v.g), tone(v.b));
    imageStore(out_image, pix, vec4(c, 1.0));
#endif
}
