#include "render/image.h"

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include <png.h>

#include "common/log.h"

bool image_init(struct image *img, int width, int height)
{
    img->width = width;
    img->height = height;
    img->rgba = calloc((size_t)width * (size_t)height * 4, sizeof(float));
    if (!img->rgba) {
        log_error("out of memory for a %dx%d image", width, height);
        return false;
    }
    return true;
}

void image_finish(struct image *img)
{
    if (!img)
        return;
    free(img->rgba);
    img->rgba = NULL;
    img->width = img->height = 0;
}

/* The steps (image.h), made once: x_k, where the operator's sRGB value times 255 is k - 1/2,
 * solved in double (s = (k - 1/2) / 255, c the sRGB curve's inverse of s, x = c / (1 - c)),
 * and the least float at or above it.  A float x is then quantized as the real function of
 * it would be (ties aside, which no float meets): monotone in x, unlike the same formula in
 * floats, whose x / (1 + x) falls by an ulp where 1 + x rounds up (64 such drops in the 8-bit
 * values between 1e-5 and 1e4). */
static float tonemap_steps[IMAGE_TONEMAP_STEPS];
static pthread_once_t tonemap_steps_once = PTHREAD_ONCE_INIT;

static void tonemap_steps_make(void)
{
    for (int k = 1; k <= IMAGE_TONEMAP_STEPS; k++) {
        double s = (k - 0.5) / 255.0;
        double c = s <= 12.92 * 0.0031308 ? s / 12.92 : pow((s + 0.055) / 1.055, 2.4);
        double x = c / (1.0 - c);
        float f = (float)x;
        if ((double)f < x)
            f = nextafterf(f, INFINITY);
        tonemap_steps[k - 1] = f;
    }
}

void image_tonemap_steps(float out[IMAGE_TONEMAP_STEPS])
{
    pthread_once(&tonemap_steps_once, tonemap_steps_make);
    memcpy(out, tonemap_steps, sizeof(tonemap_steps));
}

uint8_t image_tonemap(float linear, float exposure)
{
    pthread_once(&tonemap_steps_once, tonemap_steps_make);
    float l = linear > 0.0f && isfinite(linear) ? linear : 0.0f;
    float x = exposure * l; /* +inf (an overflow) lies above every step: white */
    unsigned v = 0;
    for (unsigned half = 128; half > 0; half >>= 1) {
        unsigned k = v + half;
        if (k <= IMAGE_TONEMAP_STEPS && x >= tonemap_steps[k - 1])
            v = k;
    }
    return (uint8_t)v;
}

static bool has_suffix(const char *s, const char *suffix)
{
    size_t a = strlen(s), b = strlen(suffix);
    return a >= b && strcasecmp(s + a - b, suffix) == 0;
}

bool image_path_supported(const char *path)
{
    return has_suffix(path, ".png") || has_suffix(path, ".pfm");
}

bool image_path_is_png(const char *path)
{
    return has_suffix(path, ".png");
}

bool image_write(const struct image *img, const char *path, float exposure)
{
    if (has_suffix(path, ".png"))
        return image_write_png(img, path, exposure);
    if (has_suffix(path, ".pfm"))
        return image_write_pfm(img, path);
    log_error("%s: unknown image type: expected a name ending in .png or .pfm", path);
    return false;
}

struct membuf {
    unsigned char *data;
    size_t len, cap;
    bool failed;
};

static void png_write_mem(png_structp png, png_bytep data, png_size_t len)
{
    struct membuf *m = png_get_io_ptr(png);
    if (m->failed)
        return;
    if (m->len + len > m->cap) {
        size_t cap = m->cap ? m->cap * 2 : 65536;
        while (cap < m->len + len)
            cap *= 2;
        unsigned char *grown = realloc(m->data, cap);
        if (!grown) {
            m->failed = true;
            return;
        }
        m->data = grown;
        m->cap = cap;
    }
    memcpy(m->data + m->len, data, len);
    m->len += len;
}

static void png_flush_mem(png_structp png)
{
    (void)png;
}

/* Encodes HEIGHT rows of WIDTH RGB bytes (ROWS[y], top to bottom) as PNG into PATH. */
static bool encode_png(png_bytep *rows, int width, int height, const char *path)
{
    struct membuf m = {0};
    bool ok = false;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!png || !info) {
        png_destroy_write_struct(&png, &info);
        log_error("%s: libpng could not start", path);
        goto done;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        log_error("%s: libpng failed to encode the image", path);
        goto done;
    }
    png_set_write_fn(png, &m, png_write_mem, png_flush_mem);
    png_set_IHDR(png, info, (png_uint_32)width, (png_uint_32)height, 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    png_write_info(png, info);
    png_write_image(png, rows);
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    if (m.failed) {
        log_error("%s: out of memory encoding the image", path);
        goto done;
    }
    ok = file_write_atomic(path, m.data, m.len);
done:
    free(m.data);
    return ok;
}

bool image_write_png(const struct image *img, const char *path, float exposure)
{
    size_t row_bytes = (size_t)img->width * 3;
    unsigned char *pixels = malloc(row_bytes * (size_t)img->height);
    png_bytep *rows = malloc(sizeof(png_bytep) * (size_t)img->height);
    bool ok = false;
    if (!pixels || !rows) {
        log_error("%s: out of memory", path);
        goto done;
    }
    for (int y = 0; y < img->height; y++) {
        /* PNG rows go top to bottom. */
        const float *src = img->rgba + (size_t)(img->height - 1 - y) * img->width * 4;
        unsigned char *dst = pixels + (size_t)y * row_bytes;
        for (int x = 0; x < img->width; x++)
            for (int c = 0; c < 3; c++)
                dst[3 * x + c] = image_tonemap(src[4 * x + c], exposure);
        rows[y] = dst;
    }
    ok = encode_png(rows, img->width, img->height, path);
done:
    free(rows);
    free(pixels);
    return ok;
}

bool image_write_png8(const uint8_t *rgba, int width, int height, const char *path)
{
    size_t row_bytes = (size_t)width * 3;
    unsigned char *pixels = malloc(row_bytes * (size_t)height);
    png_bytep *rows = malloc(sizeof(png_bytep) * (size_t)height);
    bool ok = false;
    if (!pixels || !rows) {
        log_error("%s: out of memory", path);
        goto done;
    }
    for (int y = 0; y < height; y++) {
        const uint8_t *src = rgba + (size_t)(height - 1 - y) * width * 4;
        unsigned char *dst = pixels + (size_t)y * row_bytes;
        for (int x = 0; x < width; x++)
            for (int c = 0; c < 3; c++)
                dst[3 * x + c] = src[4 * x + c];
        rows[y] = dst;
    }
    ok = encode_png(rows, width, height, path);
done:
    free(rows);
    free(pixels);
    return ok;
}

bool image_write_pfm(const struct image *img, const char *path)
{
    char header[64];
    int hlen = snprintf(header, sizeof(header), "PF\n%d %d\n-1.0\n", img->width, img->height);
    size_t count = (size_t)img->width * (size_t)img->height;
    size_t bytes = (size_t)hlen + count * 3 * sizeof(float);
    unsigned char *buf = malloc(bytes);
    if (!buf) {
        log_error("%s: out of memory", path);
        return false;
    }
    memcpy(buf, header, (size_t)hlen);
    float *dst = (float *)(void *)(buf + hlen);
    /* PFM rows go bottom to top, like ours; -1.0 says little-endian floats. */
    for (size_t i = 0; i < count; i++) {
        float rgb[3] = {img->rgba[4 * i], img->rgba[4 * i + 1], img->rgba[4 * i + 2]};
        memcpy(dst + 3 * i, rgb, sizeof(rgb));
    }
    bool ok = file_write_atomic(path, buf, bytes);
    free(buf);
    return ok;
}

static uint32_t swap32(uint32_t v)
{
    return (v >> 24) | ((v >> 8) & 0xff00u) | ((v << 8) & 0xff0000u) | (v << 24);
}

bool image_read_pfm(const char *path, struct image *img)
{
    size_t len = 0;
    char why[160];
    /* Pictures are not text: up to 2 GiB (a 16384 x 16384 RGB PFM is 3 GiB: refused). */
    char *data = file_read_text(path, (size_t)1 << 31, &len, why, sizeof(why));
    if (!data) {
        log_error("%s: %s", path, why);
        return false;
    }
    char kind[3] = {0};
    int w = 0, h = 0, consumed = 0;
    double scale = 0.0;
    bool ok = false;
    if (sscanf(data, "%2s %d %d %lf%n", kind, &w, &h, &scale, &consumed) != 4 ||
        (strcmp(kind, "PF") != 0 && strcmp(kind, "Pf") != 0) || w <= 0 || h <= 0 ||
        w > 65536 || h > 65536 || scale == 0.0) {
        log_error("%s: not a PFM image (expected \"PF\" or \"Pf\", width, height, scale)", path);
        goto done;
    }
    int channels = strcmp(kind, "PF") == 0 ? 3 : 1;
    size_t offset = (size_t)consumed + 1; /* one whitespace byte after the scale */
    size_t need = (size_t)w * (size_t)h * (size_t)channels * 4;
    if (len < offset + need) {
        log_error("%s: truncated PFM: expected %zu bytes of pixels, found %zu", path, need,
                  len > offset ? len - offset : 0);
        goto done;
    }
    if (!image_init(img, w, h))
        goto done;
    bool swap = scale > 0.0; /* positive scale: big-endian */
    const unsigned char *p = (const unsigned char *)data + offset;
    for (size_t i = 0; i < (size_t)w * (size_t)h; i++) {
        for (int c = 0; c < 3; c++) {
            uint32_t bits;
            memcpy(&bits, p + 4 * (i * (size_t)channels + (size_t)(channels == 3 ? c : 0)), 4);
            if (swap)
                bits = swap32(bits);
            float v;
            memcpy(&v, &bits, 4);
            img->rgba[4 * i + (size_t)c] = v;
        }
        img->rgba[4 * i + 3] = 1.0f;
    }
    ok = true;
done:
    free(data);
    return ok;
}

size_t image_count_nonfinite(const struct image *img)
{
    size_t bad = 0;
    for (size_t i = 0; i < (size_t)img->width * (size_t)img->height; i++) {
        if (!isfinite(img->rgba[4 * i]) || !isfinite(img->rgba[4 * i + 1]) ||
            !isfinite(img->rgba[4 * i + 2]))
            bad++;
    }
    return bad;
}

void image_blit(struct image *dst, const struct image *src, int x, int y)
{
    for (int j = 0; j < src->height; j++) {
        int dy = y + j;
        if (dy < 0 || dy >= dst->height)
            continue;
        for (int i = 0; i < src->width; i++) {
            int dx = x + i;
            if (dx < 0 || dx >= dst->width)
                continue;
            memcpy(dst->rgba + 4 * ((size_t)dy * dst->width + dx),
                   src->rgba + 4 * ((size_t)j * src->width + i), 4 * sizeof(float));
        }
    }
}
