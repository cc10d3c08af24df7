// HMD lens pre-distortion: OpenHMD's universal (PanoTools) lens model and its parameters,
// applied to one eye image, written into that eye's half of the screen image.
//
// Each screen pixel, in metres on the panel relative to the lens centre and divided by the
// warp scale (radius 1 = the inscribed circle), is pushed outward by the radial polynomial
//     r' = r (d + c |r| + b |r|^2 + a |r|^3),   [a, b, c, d] = UNIVERSAL_DISTORTION_K,
// and the eye image is read there, each colour channel with its own radial scale
// (UNIVERSAL_ABERRATION_K) to cancel the lens' chromatic aberration.  Outside the eye image
// the panel stays black.  With [0, 0, 0, 1] and [1, 1, 1] the pass is the identity.

#include "bindings.h"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = BIND_WARP_TEX_EYE) uniform sampler2D eye_tex; // linear radiance, linear filtering
layout(rgba32f, binding = BIND_WARP_IMG_OUT) uniform writeonly image2D out_image;

uniform ivec2 size;           // of the eye's region on the screen, pixels
uniform ivec2 offset;         // lower-left corner of the region in out_image
uniform vec2 viewport_scale;  // the region's size on the panel, metres
uniform vec2 lens_center;     // lens centre within the region, metres
uniform float warp_scale;     // metres that map to radius 1
uniform vec4 warp_param;      // [a, b, c, d]
uniform vec3 aberration;      // radial scale per channel

void main()
{
    ivec2 pix = ivec2(gl_GlobalInvocationID.xy);
    if (pix.x >= size.x || pix.y >= size.y)
        return;
    vec2 uv = (vec2(pix) + 0.5) / vec2(size);
    vec2 r = (uv * viewport_scale - lens_center) / warp_scale;
    float m = length(r);
    float k = warp_param.w + m * (warp_param.z + m * (warp_param.y + m * warp_param.x));
    vec2 moved = r * k * warp_scale;
    vec2 tr = (lens_center + aberration.r * moved) / viewport_scale;
    vec2 tg = (lens_center + aberration.g * moved) / viewport_scale;
    vec2 tb = (lens_center + aberration.b * moved) / viewport_scale;
    vec4 c = vec4(0.0, 0.0, 0.0, 1.0);
    if (all(greaterThanEqual(tg, vec2(0.0))) && all(lessThanEqual(tg, vec2(1.0)))) {
        vec4 g = texture(eye_tex, tg);
        c = vec4(texture(eye_tex, tr).r, g.g, texture(eye_tex, tb).b, g.a);
    }
    imageStore(out_image, pix + offset, c);
}
