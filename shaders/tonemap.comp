// Linear radiance to display sRGB: 1 - exp(-exposure L) per channel, then the sRGB curve.
// Must match image_tonemap() in src/render/image.c.

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform readonly image2D in_image;
layout(rgba8, binding = 1) uniform writeonly image2D out_image;
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
    vec3 c = 1.0 - exp(-exposure * max(l, vec3(0.0)));
    imageStore(out_image, pix, vec4(srgb(c.r), srgb(c.g), srgb(c.b), 1.0));
}
