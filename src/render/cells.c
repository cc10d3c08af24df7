/* The macro-cell pyramid of empty-space skipping (render.h, "empty-space skipping"): level 0
 * from the extinction texture (shaders/cells_build.comp), each further level the maxima of
 * the one below (shaders/cells_reduce.comp), all in one storage buffer behind a header of the
 * levels' sizes, so that the eye pass and the light build read it without uniform arrays.  The
 * same cells on the CPU (render_cells_cpu: a staged step's, and the tests' reference) from the
 * extinction in memory, uploaded into that buffer. */
#include "render/render.h"

#include <assert.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "shaders/bindings.h"

/* The buffer's header: RENDER_CELL_LEVELS ivec4 (cells along x, y, z, the level's first
 * index) and one ivec4 (levels, voxels per cell edge, 0, 0), as the shaders
 * declare it. */
#define HEADER_INTS (4 * RENDER_CELL_LEVELS + 4)

static const char *distance_defines(void)
{
    static char text[64];
    snprintf(text, sizeof(text), "#define CELL_DISTANCE_MAX %d\n", RENDER_CELL_DISTANCE_MAX);
    return text;
}

bool render_cells_programs_init(struct render_cells_programs *p)
{
    memset(p, 0, sizeof(*p));
    return gpu_program_init(&p->build[0], "cells_build.comp", "#define TEMPORAL 0\n") &&
           gpu_program_init(&p->build[1], "cells_build.comp", "#define TEMPORAL 1\n") &&
           gpu_program_init(&p->build[2], "cells_build.comp",
                            "#define TEMPORAL 0\n#define STRETCHED 1\n") &&
           gpu_program_init(&p->build[3], "cells_build.comp",
                            "#define TEMPORAL 1\n#define STRETCHED 1\n") &&
           gpu_program_init(&p->reduce, "cells_reduce.comp", NULL) &&
           gpu_program_init(&p->distance, "cells_distance.comp", distance_defines());
}

void render_cells_programs_finish(struct render_cells_programs *p)
{
    for (int i = 0; i < 4; i++)
        gpu_program_finish(&p->build[i]);
    gpu_program_finish(&p->reduce);
    gpu_program_finish(&p->distance);
}

void render_cells_layout(const int n[3], int cell_voxels, struct render_cells *c)
{
    memset(c->dims, 0, sizeof(c->dims));
    c->cell_voxels = cell_voxels;
    size_t count = 0;
    int d[3];
    for (int a = 0; a < 3; a++)
        d[a] = (n[a] + cell_voxels - 1) / cell_voxels;
    int level = 0;
    for (;;) {
        for (int a = 0; a < 3; a++)
            c->dims[level][a] = d[a];
        c->dims[level][3] = (int)count;
        count += (size_t)d[0] * d[1] * d[2];
        level++;
        if ((d[0] == 1 && d[1] == 1 && d[2] == 1) || level == RENDER_CELL_LEVELS)
            break;
        for (int a = 0; a < 3; a++)
            d[a] = (d[a] + 1) / 2;
    }
    c->levels = level;
    c->count = count;
}

/* A cell row's levels go to cells_build.comp in a uniform array of 32 (stretched grids only). */
_Static_assert((GRID3_LEVELS_MAX + RENDER_CELL_VOXELS_STRETCHED - 1) /
                       RENDER_CELL_VOXELS_STRETCHED <= 32,
               "cell_levels[] holds every cell row");

/* The levels a trilinear sample within half a (mean) voxel of cell row CZ reads, on a
 * stretched GRID with cells CELL_VOXELS mean levels tall. */
static void row_levels(const struct grid3 *grid, int cell_voxels, int cz, int range[2])
{
    double h = cell_voxels * grid->spacing[2], z0 = grid->origin[2] + cz * h;
    grid3_z_voxel_range(grid, z0 - 0.5 * grid->spacing[2], z0 + h + 0.5 * grid->spacing[2],
                        &range[0], &range[1]);
}

void render_cells_level_rows(const struct render_cells *c, const struct grid3 *grid, int *row)
{
    for (int k = 0; k < grid->n[2]; k++)
        row[k] = k / c->cell_voxels;
    if (!grid3_stretched(grid))
        return;
    /* Cells are even in height: the rows reading level k are not k / cell_voxels. */
    for (int k = 0; k < grid->n[2]; k++)
        row[k] = -1;
    for (int cz = c->dims[0][2] - 1; cz >= 0; cz--) {
        int range[2];
        row_levels(grid, c->cell_voxels, cz, range);
        for (int k = range[0]; k <= range[1]; k++)
            row[k] = cz;
    }
}

bool render_zmap_upload(const struct grid3 *grid, struct gpu_texture *tex,
                        const struct gpu_program *prog)
{
    int n = grid3_zmap_entries(grid);
    float *t = malloc((size_t)n * 4 * sizeof(float));
    if (!t) {
        log_error("out of memory for the height table");
        return false;
    }
    float *u = t + 2 * (size_t)n, *dz = u + n;
    grid3_zmap_fill(grid, n, u, dz);
    for (int i = 0; i < n; i++) { /* interleaved: r the coordinate, g the thickness */
        t[2 * i] = u[i];
        t[2 * i + 1] = dz[i];
    }
    const int size[3] = {n, 1, 1};
    bool ok = true;
    if (tex->id && tex->size[0] == n && tex->format == GPU_RG32F) {
        gpu_texture_upload(tex, t);
    } else {
        gpu_texture_finish(tex);
        ok = gpu_texture_init(tex, 1, size, GPU_RG32F, t);
    }
    free(t);
    if (ok && prog)
        render_zmap_uniforms(grid, tex, prog);
    return ok;
}

void render_zmap_uniforms(const struct grid3 *grid, const struct gpu_texture *tex,
                          const struct gpu_program *prog)
{
    gpu_uniform_int(prog, "zmap_n", tex->size[0]);
    gpu_uniform_float(prog, "zmap_inv_height", (float)(1.0 / (grid->n[2] * grid->spacing[2])));
}

bool render_cells_build_begin(struct render_cells *c, const struct gpu_texture *beta,
                              const struct grid3 *grid)
{
    bool stretched = grid && grid3_stretched(grid);
    struct render_cells layout = {0};
    render_cells_layout(beta->size, stretched ? RENDER_CELL_VOXELS_STRETCHED : RENDER_CELL_VOXELS,
                        &layout);
    size_t bytes = HEADER_INTS * sizeof(int) + layout.count * sizeof(float);
    if (!c->buf.id || c->buf.bytes != bytes) {
        gpu_buffer_finish(&c->buf);
        if (!gpu_buffer_init(&c->buf, bytes, NULL)) {
            c->levels = 0;
            return false;
        }
    }
    struct gpu_buffer buf = c->buf;
    *c = layout;
    c->buf = buf;
    c->built_layers = 0;
    c->built_rows = 0;
    int header[HEADER_INTS] = {0};
    memcpy(header, c->dims, sizeof(c->dims));
    header[4 * RENDER_CELL_LEVELS] = c->levels;
    header[4 * RENDER_CELL_LEVELS + 1] = c->cell_voxels;
    gpu_buffer_upload(&c->buf, 0, sizeof(header), header);
    return true;
}

/* Level 0's clear distances (cells_distance.comp), after the coarser levels are made.  Without
 * memory for the passes the clear cells keep 0: leapt a cell at a time, as exactly. */
static void distance_gpu(struct render_cells *c, const struct render_cells_programs *p)
{
    const int *d = c->dims[0];
    size_t n = (size_t)d[0] * d[1] * d[2];
    struct gpu_buffer scratch = {0};
    if (!gpu_buffer_init(&scratch, 2 * n * sizeof(float), NULL)) {
        log_warn("no GPU memory for the macro cells' clear distances: empty space is leapt a "
                 "cell at a time");
        return;
    }
    gpu_buffer_bind(&c->buf, BIND_CELLS_BUF_CELLS);
    gpu_buffer_bind(&scratch, BIND_CELLS_BUF_SCRATCH);
    for (int pass = 0; pass < 3; pass++) {
        gpu_uniform_int(&p->distance, "pass", pass);
        int lines = pass == 0 ? d[1] * d[2] : pass == 1 ? d[0] * d[2] : d[0] * d[1];
        gpu_dispatch(&p->distance, lines, 1, 1);
    }
    gpu_buffer_finish(&scratch);
}

bool render_cells_build_step(struct render_cells *c, const struct render_cells_programs *p,
                             const struct gpu_texture *beta, const struct gpu_texture *next,
                             const struct grid3 *grid, int layers, bool *done)
{
    return render_cells_build_piece(c, p, beta, next, grid, layers, 0, done);
}

bool render_cells_build_piece(struct render_cells *c, const struct render_cells_programs *p,
                              const struct gpu_texture *beta, const struct gpu_texture *next,
                              const struct grid3 *grid, int layers, int rows, bool *done)
{
    *done = false;
    if (c->built_layers >= c->dims[0][2]) {
        /* The coarser levels, each from the one below. */
        gpu_buffer_bind(&c->buf, BIND_CELLS_BUF_CELLS);
        for (int level = 1; level < c->levels; level++) {
            gpu_uniform_int(&p->reduce, "level", level);
            gpu_dispatch(&p->reduce, c->dims[level][0], c->dims[level][1], c->dims[level][2]);
        }
        distance_gpu(c, p);
        *done = true;
        return true;
    }
    int from = c->built_layers, count = c->dims[0][2] - from;
    if (layers > 0 && layers < count)
        count = layers;
    int y0 = c->built_rows, ny = c->dims[0][1] - y0;
    if (rows > 0 && rows < ny)
        ny = rows;
    bool stretched = grid && grid3_stretched(grid);
    const struct gpu_program *b = &p->build[(next ? 1 : 0) | (stretched ? 2 : 0)];
    gpu_uniform_ivec3(b, "vol_n", beta->size);
    for (int cz = 0; stretched && cz < c->dims[0][2]; cz++) {
        int range[2];
        row_levels(grid, c->cell_voxels, cz, range);
        char name[32];
        snprintf(name, sizeof(name), "cell_levels[%d]", cz);
        gpu_uniform_ivec2(b, name, range);
    }
    gpu_uniform_int(b, "base_z", from);
    gpu_uniform_int(b, "base_y", y0);
    gpu_texture_bind(beta, BIND_CELLS_TEX_BETA);
    if (next)
        gpu_texture_bind(next, BIND_CELLS_TEX_BETA_NEXT);
    gpu_buffer_bind(&c->buf, BIND_CELLS_BUF_CELLS);
    gpu_dispatch(b, c->dims[0][0], ny, count);
    if (y0 + ny < c->dims[0][1]) {
        c->built_rows = y0 + ny; /* the same layers' next rows next */
    } else {
        c->built_layers = from + count;
        c->built_rows = 0;
    }
    return true;
}

bool render_cells_build(struct render_cells *c, const struct render_cells_programs *p,
                        const struct gpu_texture *beta, const struct gpu_texture *next,
                        const struct grid3 *grid)
{
    bool done = false;
    return render_cells_build_begin(c, beta, grid) &&
           render_cells_build_step(c, p, beta, next, grid, 0, &done) &&
           render_cells_build_step(c, p, beta, next, grid, 0, &done);
}

bool render_cells_max(struct render_cells *c, const struct render_cells *a,
                      const struct render_cells *b, const struct gpu_texture *beta,
                      const struct grid3 *grid)
{
    if (!render_cells_build_begin(c, beta, grid))
        return false;
    if (a->count != c->count || b->count != c->count) {
        log_error("macro cells: %zu and %zu cells do not make a pair of %zu", a->count, b->count,
                  c->count);
        return false;
    }
    float *x = render_cells_read(a), *y = render_cells_read(b);
    bool ok = x && y;
    if (ok) {
        /* Every level is a maximum over the same voxels: the maximum of the two. */
        for (size_t i = 0; i < c->count; i++)
            x[i] = y[i] > x[i] ? y[i] : x[i];
        gpu_buffer_upload(&c->buf, HEADER_INTS * sizeof(int), c->count * sizeof(float), x);
        c->built_layers = c->dims[0][2];
    }
    free(x);
    free(y);
    return ok;
}

void render_cells_finish(struct render_cells *c)
{
    gpu_buffer_finish(&c->buf);
    memset(c, 0, sizeof(*c));
}

void render_cells_bind(const struct render_cells *c, const struct gpu_program *prog,
                       unsigned binding, const struct grid3 *grid)
{
    float size[3];
    for (int a = 0; a < 3; a++)
        size[a] = (float)(c->cell_voxels * grid->spacing[a]);
    gpu_uniform_vec3(prog, "cell_size", size);
    gpu_buffer_bind(&c->buf, binding);
}

float *render_cells_read(const struct render_cells *c)
{
    if (!c->buf.id)
        return NULL;
    float *out = malloc(c->count * sizeof(float));
    if (!out) {
        log_error("out of memory reading %zu macro cells", c->count);
        return NULL;
    }
    gpu_buffer_read(&c->buf, HEADER_INTS * sizeof(int), c->count * sizeof(float), out);
    return out;
}

/* ---- the same cells on the CPU ------------------------------------------------------------ */

/* A voxel's ice plus water extinction as cells_build.comp's clean() reads it. */
static inline float clean_sum(const float *b)
{
    float x = b[0] > 0.0f ? (b[0] < 1e30f ? b[0] : 1e30f) : 0.0f;
    float y = b[1] > 0.0f ? (b[1] < 1e30f ? b[1] : 1e30f) : 0.0f;
    return x + y;
}

/* The voxels along one axis of N that cell C of B voxels reads, HALO more each side. */
static void window(int c, int b, int halo, int n, int *lo, int *hi)
{
    *lo = c * b - halo < 0 ? 0 : c * b - halo;
    *hi = c * b + b - 1 + halo > n - 1 ? n - 1 : c * b + b - 1 + halo;
}

void render_cells_cpu_finish(struct render_cells_cpu *w)
{
    free(w->planes);
    free(w->row);
    free(w->cells);
    memset(w, 0, sizeof(*w));
}

bool render_cells_cpu_begin(struct render_cells_cpu *w, const struct grid3 *grid, int halo)
{
    struct render_cells layout = {0};
    int b = grid3_stretched(grid) ? RENDER_CELL_VOXELS_STRETCHED : RENDER_CELL_VOXELS;
    render_cells_layout(grid->n, b, &layout);
    bool same = w->cells && w->layout.count == layout.count &&
                w->layout.cell_voxels == layout.cell_voxels &&
                memcmp(w->layout.dims, layout.dims, sizeof(layout.dims)) == 0 &&
                memcmp(w->grid.n, grid->n, sizeof(grid->n)) == 0;
    if (!same) {
        render_cells_cpu_finish(w);
        const int *d0 = layout.dims[0], *n = grid->n;
        w->planes = malloc((size_t)n[2] * d0[0] * d0[1] * sizeof(float));
        w->row = malloc(((size_t)n[0] + (size_t)n[1] * d0[0]) * sizeof(float));
        w->cells = malloc(layout.count * sizeof(float));
        if (!w->planes || !w->row || !w->cells) {
            render_cells_cpu_finish(w);
            return false;
        }
    }
    w->layout = layout;
    w->grid = *grid;
    w->halo = halo;
    w->planes_done = 0;
    return true;
}

void render_cells_cpu_planes(struct render_cells_cpu *w, const float *beta, int from, int to)
{
    const int *n = w->grid.n, *d0 = w->layout.dims[0];
    const int b = w->layout.cell_voxels, halo = w->halo, dx = d0[0], dy = d0[1];
    float *row = w->row, *xr = w->row + n[0];
    for (int z = from; z < to; z++) {
        const float *plane = beta + 2 * (size_t)n[0] * n[1] * z;
        /* Along x: each row's cells' windows. */
        for (int y = 0; y < n[1]; y++) {
            const float *v = plane + 2 * (size_t)n[0] * y;
            for (int x = 0; x < n[0]; x++)
                row[x] = clean_sum(v + 2 * x);
            for (int cx = 0; cx < dx; cx++) {
                int lo, hi;
                window(cx, b, halo, n[0], &lo, &hi);
                float m = 0.0f;
                for (int x = lo; x <= hi; x++)
                    m = row[x] > m ? row[x] : m;
                xr[(size_t)y * dx + cx] = m;
            }
        }
        /* Along y: the plane's share of every cell of a layer. */
        float *out = w->planes + (size_t)z * dx * dy;
        for (int cy = 0; cy < dy; cy++) {
            float *o = out + (size_t)cy * dx;
            int lo, hi;
            window(cy, b, halo, n[1], &lo, &hi);
            for (int cx = 0; cx < dx; cx++)
                o[cx] = 0.0f;
            for (int y = lo; y <= hi; y++) {
                const float *r = xr + (size_t)y * dx;
                for (int cx = 0; cx < dx; cx++)
                    o[cx] = r[cx] > o[cx] ? r[cx] : o[cx];
            }
        }
    }
    if (to > w->planes_done)
        w->planes_done = to;
}

void render_cells_cpu_levels(struct render_cells_cpu *w)
{
    assert(w->planes_done == w->grid.n[2]);
    const struct render_cells *c = &w->layout;
    const int *d0 = c->dims[0], nz = w->grid.n[2];
    const size_t plane = (size_t)d0[0] * d0[1];
    bool stretched = grid3_stretched(&w->grid);
    for (int cz = 0; cz < d0[2]; cz++) {
        int range[2];
        if (stretched)
            row_levels(&w->grid, c->cell_voxels, cz, range); /* as cell_levels[] has it */
        else
            window(cz, c->cell_voxels, w->halo, nz, &range[0], &range[1]);
        assert(range[0] >= 0 && range[1] < nz);
        float *o = w->cells + (size_t)cz * plane;
        for (size_t i = 0; i < plane; i++)
            o[i] = 0.0f;
        for (int z = range[0]; z <= range[1]; z++) {
            const float *p = w->planes + (size_t)z * plane;
            for (size_t i = 0; i < plane; i++)
                o[i] = p[i] > o[i] ? p[i] : o[i];
        }
    }
    /* Each further level as cells_reduce.comp makes it. */
    for (int level = 1; level < c->levels; level++) {
        const int *d = c->dims[level], *e = c->dims[level - 1];
        for (int cz = 0; cz < d[2]; cz++)
            for (int cy = 0; cy < d[1]; cy++)
                for (int cx = 0; cx < d[0]; cx++) {
                    float m = 0.0f;
                    for (int z = 2 * cz; z <= 2 * cz + 1 && z < e[2]; z++)
                        for (int y = 2 * cy; y <= 2 * cy + 1 && y < e[1]; y++)
                            for (int x = 2 * cx; x <= 2 * cx + 1 && x < e[0]; x++) {
                                float v =
                                    w->cells[e[3] + x + (size_t)e[0] * (y + (size_t)e[1] * z)];
                                m = v > m ? v : m;
                            }
                    w->cells[d[3] + cx + (size_t)d[0] * (cy + (size_t)d[1] * cz)] = m;
                }
    }
    render_cells_distance_cpu(c, w->cells); /* after the levels, as on the GPU */
}

void render_cells_distance_cpu(const struct render_cells *c, float *cells)
{
    const int *d = c->dims[0];
    const int far = RENDER_CELL_DISTANCE_MAX + 1;
    const size_t n = (size_t)d[0] * d[1] * d[2];
    float *v = cells + d[3];
    /* Two raster passes with the 26 neighbours at a distance of 1 each (a chamfer of the
     * chessboard metric, exact in it): first the 13 neighbours before a cell in x, y, z order,
     * then the 13 after it in the reverse order.  Distances as floats, 0 in occupied cells. */
    float *dist = malloc(n * sizeof(float));
    if (!dist) {
        log_error("out of memory for the distances of %zu macro cells", n);
        return; /* cells holding 0: leapt a cell at a time, as exact */
    }
    for (size_t i = 0; i < n; i++)
        dist[i] = v[i] > 0.0f ? 0.0f : (float)far;
    for (int pass = 0; pass < 2; pass++) {
        int s = pass ? -1 : 1;
        for (int zi = 0; zi < d[2]; zi++) {
            int z = pass ? d[2] - 1 - zi : zi;
            for (int yi = 0; yi < d[1]; yi++) {
                int y = pass ? d[1] - 1 - yi : yi;
                for (int xi = 0; xi < d[0]; xi++) {
                    int x = pass ? d[0] - 1 - xi : xi;
                    size_t i = (size_t)x + (size_t)d[0] * (y + (size_t)d[1] * z);
                    float m = dist[i];
                    /* The neighbours that come before in this pass's order. */
                    for (int dz = -1; dz <= 0 && m > 0.0f; dz++)
                        for (int dy = -1; dy <= 1; dy++)
                            for (int dx = -1; dx <= 1; dx++) {
                                if (dz == 0 && (dy > 0 || (dy == 0 && dx >= 0)))
                                    continue;
                                int nx = x + s * dx, ny = y + s * dy, nz = z + s * dz;
                                if (nx < 0 || ny < 0 || nz < 0 || nx >= d[0] || ny >= d[1] ||
                                    nz >= d[2])
                                    continue;
                                float e =
                                    dist[(size_t)nx + (size_t)d[0] * (ny + (size_t)d[1] * nz)] +
                                    1.0f;
                                m = e < m ? e : m;
                            }
                    dist[i] = m;
                }
            }
        }
    }
    for (size_t i = 0; i < n; i++)
        if (v[i] <= 0.0f)
            v[i] = -dist[i];
    free(dist);
}

float *render_cells_cpu(const struct ext_volume *vol, const struct ext_volume *next, int halo,
                        struct render_cells *layout)
{
    struct render_cells_cpu w[2] = {0};
    for (int k = 0; k < (next ? 2 : 1); k++) {
        const struct ext_volume *v = k ? next : vol;
        if (!render_cells_cpu_begin(&w[k], &vol->grid, halo)) {
            log_error("out of memory for the macro cells of %d x %d x %d voxels",
                      vol->grid.n[0], vol->grid.n[1], vol->grid.n[2]);
            render_cells_cpu_finish(&w[0]);
            return NULL;
        }
        render_cells_cpu_planes(&w[k], v->beta, 0, vol->grid.n[2]);
        render_cells_cpu_levels(&w[k]);
    }
    float *out = w[0].cells;
    /* Every cell is a maximum over the same voxels in both: the larger of the two. */
    for (size_t i = 0; next && i < w[0].layout.count; i++)
        out[i] = w[1].cells[i] > out[i] ? w[1].cells[i] : out[i];
    *layout = w[0].layout;
    w[0].cells = NULL;
    render_cells_cpu_finish(&w[0]);
    render_cells_cpu_finish(&w[1]);
    return out;
}

bool render_cells_upload(struct render_cells *c, const struct gpu_texture *beta,
                         const struct grid3 *grid, const float *values, size_t count)
{
    if (!render_cells_build_begin(c, beta, grid))
        return false;
    if (count != c->count) {
        log_error("macro cells: %zu values for %zu cells", count, c->count);
        return false;
    }
    gpu_buffer_upload(&c->buf, HEADER_INTS * sizeof(int), count * sizeof(float), values);
    c->built_layers = c->dims[0][2];
    return true;
}
