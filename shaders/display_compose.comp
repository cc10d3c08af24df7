// Stereo composition of two eye images (linear radiance) into a region of a screen image.
// mode 0: copy the left image (side-by-side halves, quad-buffer fallbacks, plain copies).
// mode 1: red/cyan anaglyph, half-colour: red carries the left eye's luminance (so colours do
//         not fight between the eyes), green and blue come from the right eye.

#include "bindings.h"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = BIND_COMPOSE_TEX_LEFT) uniform sampler2D left_tex;
layout(binding = BIND_COMPOSE_TEX_RIGHT) uniform sampler2D right_tex;
layout(rgba32f, binding = BIND_COMPOSE_IMG_OUT) uniform writeonly image2D out_image;

uniform int mode;
uniform ivec2 size;   // of the eye images and of the region written
uniform ivec2 offset; // lower-left corner of the region in out_image

void main()
{
    ivec2 pix = ivec2(gl_GlobalInvocationID.xy);
    if (pix.x >= size.x || pix.y >= size.y)
        return;
    vec4 l = texelFetch(left_tex, pix, 0);
    vec4 c = l;
    if (mode == 1) {
        vec4 r = texelFetch(right_tex, pix, 0);
        float luma = dot(l.rgb, vec3(0.299, 0.587, 0.114));
        c = vec4(luma, r.g, r.b, 0.5 * (l.a + r.a));
    }
    imageStore(out_image, pix + offset, c);
}
