#include "render/terrain.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common/glyphs.h"
#include "common/log.h"

#define ATLAS_SIZE 512
#define GLYPH_PIXELS 48.0f
#define FIRST_CHAR 32
#define CHAR_COUNT 145 /* ' ' .. U+00B0 DEGREE SIGN */
#define DEGREE_SIGN 176

static const float wall_albedo[3] = {0.07f, 0.055f, 0.04f};

static void set_vertex(struct render_vertex *v, double x, double y, double z, const float n[3],
                       const float c[3])
{
    *v = (struct render_vertex){
        .pos = {(float)x, (float)y, (float)z},
        .normal = {n[0], n[1], n[2]},
        .color = {c[0], c[1], c[2], 1.0f},
    };
}

struct render_mesh *render_terrain_mesh(const struct terrain *t, double height_scale,
                                        double skirt_m, const float skirt_albedo[3])
{
    int nx = t->nx, ny = t->ny;
    size_t n_border = 2 * (size_t)(nx - 1) + 2 * (size_t)(ny - 1);
    size_t nv = (size_t)nx * ny + 8 + 4 * n_border;
    size_t ni = (size_t)(nx - 1) * (ny - 1) * 6 + 8 * 3 + 6 * n_border;
    struct render_vertex *v = malloc(nv * sizeof(*v));
    uint32_t *idx = malloc(ni * sizeof(*idx));
    if (!v || !idx) {
        log_error("out of memory for the terrain mesh");
        free(v);
        free(idx);
        return NULL;
    }
    for (int j = 0; j < ny; j++) {
        for (int i = 0; i < nx; i++) {
            size_t k = (size_t)j * nx + i;
            /* Central differences of the scaled heights (one-sided at the border). */
            int i0 = i > 0 ? i - 1 : i, i1 = i < nx - 1 ? i + 1 : i;
            int j0 = j > 0 ? j - 1 : j, j1 = j < ny - 1 ? j + 1 : j;
            double gx = (t->height[(size_t)j * nx + i1] - t->height[(size_t)j * nx + i0]) *
                        height_scale / fmax(t->x[i1] - t->x[i0], 1e-6);
            double gy = (t->height[(size_t)j1 * nx + i] - t->height[(size_t)j0 * nx + i]) *
                        height_scale / fmax(t->y[j1] - t->y[j0], 1e-6);
            double len = sqrt(gx * gx + gy * gy + 1.0);
            float n[3] = {(float)(-gx / len), (float)(-gy / len), (float)(1.0 / len)};
            float c[3];
            terrain_albedo((enum terrain_kind)t->kind[k], t->height[k], c);
            set_vertex(&v[k], t->x[i], t->y[j], t->height[k] * height_scale, n, c);
        }
    }
    size_t m = 0;
    for (int j = 0; j < ny - 1; j++) {
        for (int i = 0; i < nx - 1; i++) {
            uint32_t a = (uint32_t)(j * nx + i), b = a + 1, c = a + (uint32_t)nx, d = c + 1;
            const uint32_t quad[6] = {a, b, d, a, d, c};
            memcpy(idx + m, quad, sizeof(quad));
            m += 6;
        }
    }
    /* The skirt: four trapezoids from the terrain's rectangle out to SKIRT_M beyond it. */
    const float up[3] = {0, 0, 1};
    double x0 = t->x[0], x1 = t->x[nx - 1], y0 = t->y[0], y1 = t->y[ny - 1];
    const double ring[8][2] = {
        {x0, y0}, {x1, y0}, {x1, y1}, {x0, y1},
        {x0 - skirt_m, y0 - skirt_m}, {x1 + skirt_m, y0 - skirt_m},
        {x1 + skirt_m, y1 + skirt_m}, {x0 - skirt_m, y1 + skirt_m},
    };
    uint32_t base = (uint32_t)nx * (uint32_t)ny;
    for (int r = 0; r < 8; r++)
        set_vertex(&v[base + r], ring[r][0], ring[r][1], 0.0, up, skirt_albedo);
    for (uint32_t s = 0; s < 4; s++) {
        uint32_t a = base + s, b = base + (s + 1) % 4, c = a + 4, d = b + 4;
        const uint32_t quad[6] = {c, d, b, c, b, a};
        memcpy(idx + m, quad, sizeof(quad));
        m += 6;
    }
    /* Walls from the terrain's border down to the skirt, so that raised terrain (exaggerated
     * or a plateau) is a closed block and no ray slips under it. */
    uint32_t w = base + 8;
    for (int side = 0; side < 4; side++) {
        bool along_x = side % 2 == 0;
        int count = along_x ? nx - 1 : ny - 1;
        for (int e = 0; e < count; e++) {
            int i0, j0, i1, j1;
            if (along_x) { /* south (side 0) and north (side 2) edges */
                j0 = j1 = side == 0 ? 0 : ny - 1;
                i0 = e;
                i1 = e + 1;
            } else { /* east (side 1) and west (side 3) edges */
                i0 = i1 = side == 1 ? nx - 1 : 0;
                j0 = e;
                j1 = e + 1;
            }
            const float normals[4][3] = {{0, -1, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}};
            const float *n = normals[side];
            double h0 = t->height[(size_t)j0 * nx + i0] * height_scale;
            double h1 = t->height[(size_t)j1 * nx + i1] * height_scale;
            set_vertex(&v[w], t->x[i0], t->y[j0], h0, n, wall_albedo);
            set_vertex(&v[w + 1], t->x[i1], t->y[j1], h1, n, wall_albedo);
            set_vertex(&v[w + 2], t->x[i1], t->y[j1], 0.0, n, wall_albedo);
            set_vertex(&v[w + 3], t->x[i0], t->y[j0], 0.0, n, wall_albedo);
            const uint32_t quad[6] = {w, w + 1, w + 2, w, w + 2, w + 3};
            memcpy(idx + m, quad, sizeof(quad));
            m += 6;
            w += 4;
        }
    }
    struct render_mesh *mesh = render_mesh_create(v, (int)nv, idx, (int)m, false, false);
    free(v);
    free(idx);
    return mesh;
}

struct render_mesh *render_lines_mesh(const float *segments, int n_segments, const float color[3])
{
    if (n_segments <= 0)
        return NULL;
    size_t nv = (size_t)n_segments * 2;
    struct render_vertex *v = malloc(nv * sizeof(*v));
    uint32_t *idx = malloc(nv * sizeof(*idx));
    if (!v || !idx) {
        log_error("out of memory for a line mesh");
        free(v);
        free(idx);
        return NULL;
    }
    const float up[3] = {0, 0, 1};
    for (size_t i = 0; i < nv; i++) {
        set_vertex(&v[i], segments[3 * i], segments[3 * i + 1], segments[3 * i + 2], up, color);
        idx[i] = (uint32_t)i;
    }
    struct render_mesh *mesh = render_mesh_create(v, (int)nv, idx, (int)nv, true, false);
    free(v);
    free(idx);
    return mesh;
}

struct render_text {
    struct gpu_texture atlas;
    struct render_mesh *mesh;
};

/* The baked glyph index of the next character of S (UTF-8: ASCII and the degree sign), or -1
 * to skip it; advances *S. */
static int next_glyph(const char **s)
{
    const unsigned char *p = (const unsigned char *)*s;
    int cp;
    if (p[0] < 0x80) {
        cp = p[0];
        *s += 1;
    } else if ((p[0] & 0xe0) == 0xc0 && p[1]) {
        cp = ((p[0] & 0x1f) << 6) | (p[1] & 0x3f);
        *s += 2;
    } else {
        *s += 1;
        return -1;
    }
    if (cp < FIRST_CHAR || cp >= FIRST_CHAR + CHAR_COUNT || (cp > 126 && cp != DEGREE_SIGN))
        return -1;
    return cp - FIRST_CHAR;
}

struct render_text *render_text_create(const char *font_path, const struct render_label *labels,
                                       int n, const float color[3])
{
    struct glyph_atlas *font =
        glyph_atlas_create(font_path, GLYPH_PIXELS, FIRST_CHAR, CHAR_COUNT, ATLAS_SIZE, ATLAS_SIZE);
    if (!font)
        return NULL;
    struct render_text *t = calloc(1, sizeof(*t));
    unsigned char *rgba = malloc(ATLAS_SIZE * ATLAS_SIZE * 4);
    size_t glyphs = 0;
    for (int l = 0; l < n; l++)
        glyphs += strlen(labels[l].text);
    struct render_vertex *v = malloc((glyphs * 4 + 1) * sizeof(*v));
    uint32_t *idx = malloc((glyphs * 6 + 1) * sizeof(*idx));
    if (!t || !rgba || !v || !idx) {
        log_error("out of memory for labels");
        goto error;
    }
    const unsigned char *alpha = glyph_atlas_alpha(font);
    for (int p = 0; p < ATLAS_SIZE * ATLAS_SIZE; p++) {
        rgba[4 * p] = rgba[4 * p + 1] = rgba[4 * p + 2] = 255;
        rgba[4 * p + 3] = alpha[p];
    }
    int size[3] = {ATLAS_SIZE, ATLAS_SIZE, 1};
    if (!gpu_texture_init(&t->atlas, 2, size, GPU_RGBA8, rgba))
        goto error;
    const float up[3] = {0, 0, 1};
    int nv = 0, ni = 0;
    for (int l = 0; l < n; l++) {
        double s = labels[l].height_m / GLYPH_PIXELS; /* metres per atlas pixel */
        float px = 0.0f, py = 0.0f;
        for (const char *c = labels[l].text; *c;) {
            int g = next_glyph(&c);
            if (g < 0)
                continue;
            struct glyph_quad q;
            glyph_atlas_place(font, g, &px, &py, &q);
            /* Atlas y grows downward; the label's "up" is +y in the world. */
            const double corner[4][4] = {
                {q.x0, q.y1, q.s0, q.t1}, {q.x1, q.y1, q.s1, q.t1},
                {q.x1, q.y0, q.s1, q.t0}, {q.x0, q.y0, q.s0, q.t0},
            };
            for (int k = 0; k < 4; k++) {
                set_vertex(&v[nv + k], labels[l].pos[0] + corner[k][0] * s,
                           labels[l].pos[1] - corner[k][1] * s, labels[l].pos[2], up, color);
                v[nv + k].uv[0] = (float)corner[k][2];
                v[nv + k].uv[1] = (float)corner[k][3];
            }
            const uint32_t quad[6] = {0, 1, 2, 0, 2, 3};
            for (int k = 0; k < 6; k++)
                idx[ni + k] = (uint32_t)nv + quad[k];
            nv += 4;
            ni += 6;
        }
    }
    if (ni == 0) {
        log_error("no label text to draw");
        goto error;
    }
    t->mesh = render_mesh_create(v, nv, idx, ni, false, false);
    if (!t->mesh)
        goto error;
    render_mesh_set_texture(t->mesh, &t->atlas);
    glyph_atlas_destroy(font);
    free(rgba);
    free(v);
    free(idx);
    return t;

error:
    render_text_destroy(t);
    glyph_atlas_destroy(font);
    free(rgba);
    free(v);
    free(idx);
    return NULL;
}

void render_text_destroy(struct render_text *t)
{
    if (!t)
        return;
    render_mesh_destroy(t->mesh);
    gpu_texture_finish(&t->atlas);
    free(t);
}

struct render_mesh *render_text_mesh(struct render_text *t)
{
    return t->mesh;
}
