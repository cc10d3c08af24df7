/*
 * render/image: pictures on disk.  Linear float RGBA images (rows bottom to top, as GL
 * stores them) written as PNG (tone-mapped sRGB, through libpng) or PFM (linear float
 * radiance), both atomically: a failed write leaves any existing file untouched.  No GL.
 */
#ifndef ANVIL_RENDER_IMAGE_H
#define ANVIL_RENDER_IMAGE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

struct image {
    int width, height;
    float *rgba; /* width * height * 4, row 0 at the bottom */
};

bool image_init(struct image *img, int width, int height);
void image_finish(struct image *img);

/* Tone mapping shared with shaders/tonemap.comp: c = x / (1 + x), x = exposure L (Reinhard
 * et al. 2002, the global operator: highlights roll off instead of clipping), then sRGB, to
 * 8 bits: the value is the number of the steps below at or under x, so that it is the real
 * function's, rounded to nearest, of the float x (monotone), and a GPU that counts the same
 * steps gives the same bytes whatever its pow rounds to.  A negative or non-finite L reads 0. */
uint8_t image_tonemap(float linear, float exposure);

/* OUT[k - 1], k = 1 .. 255: the least float x at which image_tonemap(x, 1) reaches k
 * (ascending; made once, in double, thread safe). */
#define IMAGE_TONEMAP_STEPS 255
void image_tonemap_steps(float out[IMAGE_TONEMAP_STEPS]);

/* Writes by extension: ".png" tone-mapped with EXPOSURE, ".pfm" linear RGB.  Anything else
 * is an error naming the path and the accepted extensions. */
bool image_write(const struct image *img, const char *path, float exposure);
/* Whether image_write knows PATH's extension. */
bool image_path_supported(const char *path);
bool image_write_png(const struct image *img, const char *path, float exposure);
/* Whether PATH names a PNG file (ends in .png, any case). */
bool image_path_is_png(const char *path);
/* The same from pixels already tone-mapped (renderer_tonemap_read): WIDTH x HEIGHT RGBA bytes,
 * rows bottom to top as the image's; alpha is not written. */
bool image_write_png8(const uint8_t *rgba, int width, int height, const char *path);
bool image_write_pfm(const struct image *img, const char *path);

/* Reads a PFM written by image_write_pfm (or any little/big-endian "PF"/"Pf" file) into IMG
 * (alpha = 1).  Logs and returns false on a malformed file. */
bool image_read_pfm(const char *path, struct image *img);

/* Pixels whose RGB is not finite. */
size_t image_count_nonfinite(const struct image *img);

/* Places SRC into DST with its lower-left corner at (X, Y); clips at DST's edges. */
void image_blit(struct image *dst, const struct image *src, int x, int y);

#endif
