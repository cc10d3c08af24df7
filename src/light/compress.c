/* Node compression of visibility functions (Nes §5.3.4, Lokovic-Veach) and their lookup. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "light/light.h"

/* Up to two values per sample, compressed together: a segment goes on while every value's
 * slopes still meet (light_compress_column with one, light_compress_column2 with two). */
#define MAX_CHANNELS 2

static void emit(float *out, int *m, int k, double depth, const double *value)
{
    float *o = out + (size_t)(1 + k) * (size_t)*m;
    o[0] = (float)depth;
    for (int c = 0; c < k; c++)
        o[1 + c] = (float)value[c];
    (*m)++;
}

static double clampd(double x, double lo, double hi)
{
    return x < lo ? lo : x > hi ? hi : x;
}

/* Whether every value's slope range [LO, HI] holds 0: the function is flat within epsilon. */
static bool flat(const double *lo, const double *hi, int k)
{
    for (int c = 0; c < k; c++) {
        if (!(lo[c] <= 0.0 && hi[c] >= 0.0))
            return false;
    }
    return true;
}

static int compress_channels(const float *depth, const float *const *value, int k, int count,
                             double epsilon, float *out)
{
    if (!(epsilon >= 0.0) || !isfinite(epsilon)) {
        log_error("light map compression: epsilon %g must be finite and >= 0", epsilon);
        return -1;
    }
    for (int c = 0; c < count; c++) {
        bool finite = isfinite(depth[c]);
        for (int ch = 0; ch < k; ch++)
            finite = finite && isfinite(value[ch][c]);
        if (!finite || (c > 0 && depth[c] < depth[c - 1])) {
            log_error("light map compression: sample %d is not finite or its depth decreases", c);
            return -1;
        }
    }
    if (count <= 0)
        return 0;

    int m = 0;
    double pd = depth[0], pv[MAX_CHANNELS]; /* the current segment's start node */
    for (int ch = 0; ch < k; ch++)
        pv[ch] = value[ch][0];
    emit(out, &m, k, pd, pv);
    double lo[MAX_CHANNELS], hi[MAX_CHANNELS]; /* feasible slopes from the node */
    for (int ch = 0; ch < k; ch++)
        lo[ch] = -INFINITY, hi[ch] = INFINITY;
    int members = 0; /* samples after the node in the segment */

    for (int c = 1; c < count; c++) {
        double dc = depth[c];
        if (members > 0) {
            double dd = dc - pd; /* > 0: members lie deeper than the node, depths sorted */
            double slo[MAX_CHANNELS], shi[MAX_CHANNELS];
            bool joins = true;
            for (int ch = 0; ch < k; ch++) {
                double vc = value[ch][c];
                slo[ch] = fmax(lo[ch], (vc - epsilon - pv[ch]) / dd); /* Nes eq. 5.15 */
                shi[ch] = fmin(hi[ch], (vc + epsilon - pv[ch]) / dd); /* Nes eq. 5.14 */
                joins = joins && slo[ch] <= shi[ch];
            }
            if (joins) {
                for (int ch = 0; ch < k; ch++)
                    lo[ch] = slo[ch], hi[ch] = shi[ch]; /* every hoop so far is passed */
                members++;
                continue;
            }
            /* Sample c cannot join: end the segment at the previous sample, on a slope every
             * member accepts (the one nearest the sample's own slope), so all members stay
             * within epsilon (Lokovic-Veach; Nes eq. 5.16-5.17 are the hoops). */
            double dp = depth[c - 1], sl[MAX_CHANNELS];
            for (int ch = 0; ch < k; ch++)
                sl[ch] = clampd((value[ch][c - 1] - pv[ch]) / (dp - pd), lo[ch], hi[ch]);
            if (m == 1 && flat(lo, hi, k)) {
                /* A flat start: the next node alone stands for it, as lookups clamp to the
                 * first node's value before it. */
                for (int ch = 0; ch < k; ch++)
                    sl[ch] = 0.0;
                m = 0;
            }
            for (int ch = 0; ch < k; ch++)
                pv[ch] = pv[ch] + sl[ch] * (dp - pd);
            pd = dp;
            emit(out, &m, k, pd, pv);
            for (int ch = 0; ch < k; ch++)
                lo[ch] = -INFINITY, hi[ch] = INFINITY;
            members = 0;
        }
        double dd = dc - pd;
        if (dd <= 0.0) {
            /* Same depth as the node: merge when within epsilon, else a step (two nodes at one
             * depth).  Never divides by the zero depth difference. */
            bool near = true;
            for (int ch = 0; ch < k; ch++)
                near = near && fabs(value[ch][c] - pv[ch]) <= epsilon;
            if (!near) {
                for (int ch = 0; ch < k; ch++)
                    pv[ch] = value[ch][c];
                emit(out, &m, k, pd, pv);
            }
            continue;
        }
        for (int ch = 0; ch < k; ch++) {
            double vc = value[ch][c];
            lo[ch] = (vc - epsilon - pv[ch]) / dd;
            hi[ch] = (vc + epsilon - pv[ch]) / dd;
        }
        members = 1;
    }
    /* A flat tail needs no closing node: lookups clamp to the last node's value after it. */
    if (members > 0 && !flat(lo, hi, k)) {
        double dl = depth[count - 1], v[MAX_CHANNELS];
        for (int ch = 0; ch < k; ch++) {
            double sl = clampd((value[ch][count - 1] - pv[ch]) / (dl - pd), lo[ch], hi[ch]);
            v[ch] = pv[ch] + sl * (dl - pd);
        }
        emit(out, &m, k, dl, v);
    }
    return m;
}

int light_compress_column(const float *depth, const float *value, int count, double epsilon,
                          float *out)
{
    const float *values[1] = {value};
    return compress_channels(depth, values, 1, count, epsilon, out);
}

int light_compress_column2(const float *depth, const float *value0, const float *value1,
                           int count, double epsilon, float *out)
{
    const float *values[2] = {value0, value1};
    return compress_channels(depth, values, 2, count, epsilon, out);
}

float light_column_eval(const float *nodes, uint32_t count, float depth)
{
    if (count == 0)
        return 1.0f;
    float v;
    if (!(depth > nodes[0])) {
        v = nodes[1];
    } else if (depth >= nodes[2 * (count - 1)]) {
        v = nodes[2 * (count - 1) + 1];
    } else {
        /* The last node with depth <= DEPTH: nodes[2 a] <= depth < nodes[2 b]. */
        uint32_t a = 0, b = count - 1;
        while (b - a > 1) {
            uint32_t mid = a + (b - a) / 2;
            if (nodes[2 * mid] <= depth)
                a = mid;
            else
                b = mid;
        }
        float d0 = nodes[2 * a], d1 = nodes[2 * b];
        float v0 = nodes[2 * a + 1], v1 = nodes[2 * b + 1];
        float span = d1 - d0; /* > 0: d0 <= depth < d1 */
        v = v0 + (v1 - v0) * ((depth - d0) / span);
    }
    return fminf(fmaxf(v, 0.0f), 1.0f);
}

void light_compressed_finish(struct light_compressed *c)
{
    if (!c)
        return;
    free(c->columns);
    free(c->nodes);
    free(c->diffuse_columns);
    free(c->diffuse_nodes);
    memset(c, 0, sizeof(*c));
}

/* Compresses every column of the K-channel node values (K = 1: the light, i fastest; K = 2:
 * the diffuse light's M and N, interleaved) into COLUMNS and *NODES (grown as needed);
 * *COUNT the nodes. */
static bool compress_all(const struct light_grid *g, const float *values, int k, double epsilon,
                         uint32_t *columns, float **nodes, size_t *count)
{
    const int n0 = g->n[0], n1 = g->n[1], n2 = g->n[2];
    size_t ncol = (size_t)n0 * n1, plane = ncol;
    size_t cap = ncol * 4; /* grown on demand; smooth maps need a few nodes per column */
    int stride = 1 + k;
    float *depth = malloc((size_t)n2 * sizeof(float));
    float *v0 = malloc((size_t)n2 * sizeof(float));
    float *v1 = malloc((size_t)n2 * sizeof(float));
    float *tmp = malloc((size_t)n2 * (size_t)stride * sizeof(float));
    *nodes = malloc(cap * (size_t)stride * sizeof(float));
    *count = 0;
    bool ok = false;
    if (!depth || !v0 || !v1 || !tmp || !*nodes) {
        log_error("light map compression: out of memory for %d x %d columns", n0, n1);
        goto done;
    }
    for (int kk = 0; kk < n2; kk++)
        depth[kk] = (float)kk;
    for (int j = 0; j < n1; j++) {
        for (int i = 0; i < n0; i++) {
            size_t c = (size_t)i + (size_t)n0 * j;
            for (int kk = 0; kk < n2; kk++) {
                size_t at = c + plane * (size_t)kk;
                v0[kk] = values[(size_t)k * at];
                if (k == 2)
                    v1[kk] = values[2 * at + 1];
            }
            int m = k == 1 ? light_compress_column(depth, v0, n2, epsilon, tmp)
                           : light_compress_column2(depth, v0, v1, n2, epsilon, tmp);
            if (m < 0)
                goto done;
            if (*count + (size_t)m > UINT32_MAX) {
                log_error("light map compression: more than 2^32 nodes");
                goto done;
            }
            if (*count + (size_t)m > cap) {
                while (*count + (size_t)m > cap)
                    cap *= 2;
                float *grown = realloc(*nodes, cap * (size_t)stride * sizeof(float));
                if (!grown) {
                    log_error("light map compression: out of memory for %zu nodes", cap);
                    goto done;
                }
                *nodes = grown;
            }
            columns[2 * c] = (uint32_t)*count;
            columns[2 * c + 1] = (uint32_t)m;
            memcpy(*nodes + (size_t)stride * *count, tmp, (size_t)m * stride * sizeof(float));
            *count += (size_t)m;
        }
    }
    float *fit = realloc(*nodes, (*count ? *count : 1) * (size_t)stride * sizeof(float));
    if (fit)
        *nodes = fit;
    ok = true;
done:
    free(depth);
    free(v0);
    free(v1);
    free(tmp);
    return ok;
}

bool light_compressed_build(const struct light_map *map, double epsilon,
                            struct light_compressed *out)
{
    memset(out, 0, sizeof(*out));
    out->grid = map->grid;
    out->epsilon = epsilon;
    size_t ncol = (size_t)map->grid.n[0] * map->grid.n[1];
    out->columns = malloc(ncol * 2 * sizeof(uint32_t));
    if (map->diffuse)
        out->diffuse_columns = malloc(ncol * 2 * sizeof(uint32_t));
    if (!out->columns || (map->diffuse && !out->diffuse_columns)) {
        log_error("light map compression: out of memory for %zu columns", ncol);
        light_compressed_finish(out);
        return false;
    }
    if (!compress_all(&map->grid, map->light, 1, epsilon, out->columns, &out->nodes,
                      &out->node_count) ||
        (map->diffuse &&
         !compress_all(&map->grid, map->diffuse, 2, epsilon, out->diffuse_columns,
                       &out->diffuse_nodes, &out->diffuse_node_count))) {
        light_compressed_finish(out);
        return false;
    }
    return true;
}

static float column_at(const struct light_compressed *c, int i, int j, float depth)
{
    size_t col = (size_t)i + (size_t)c->grid.n[0] * j;
    return light_column_eval(c->nodes + 2 * (size_t)c->columns[2 * col], c->columns[2 * col + 1],
                             depth);
}

float light_compressed_sample(const struct light_compressed *c, const float tex[3])
{
    float tx, ty;
    int i = light_tex_node(tex[0], c->grid.n[0], &tx);
    int j = light_tex_node(tex[1], c->grid.n[1], &ty);
    float depth =
        fminf(fmaxf(tex[2] * (float)c->grid.n[2] - 0.5f, 0.0f), (float)(c->grid.n[2] - 1));
    float v00 = column_at(c, i, j, depth), v10 = column_at(c, i + 1, j, depth);
    float v01 = column_at(c, i, j + 1, depth), v11 = column_at(c, i + 1, j + 1, depth);
    float r0 = v00 + tx * (v10 - v00);
    float r1 = v01 + tx * (v11 - v01);
    return r0 + ty * (r1 - r0);
}

/* The diffuse light of column (I, J) at DEPTH: as light_column_eval, two values, unclamped. */
static void diffuse_column_at(const struct light_compressed *c, int i, int j, float depth,
                              float out[2])
{
    size_t col = (size_t)i + (size_t)c->grid.n[0] * j;
    uint32_t count = c->diffuse_columns[2 * col + 1];
    const float *nodes = c->diffuse_nodes + 3 * (size_t)c->diffuse_columns[2 * col];
    if (count == 0) {
        out[0] = out[1] = 0.0f;
        return;
    }
    if (!(depth > nodes[0])) {
        out[0] = nodes[1], out[1] = nodes[2];
        return;
    }
    if (depth >= nodes[3 * (count - 1)]) {
        out[0] = nodes[3 * (count - 1) + 1], out[1] = nodes[3 * (count - 1) + 2];
        return;
    }
    uint32_t a = 0, b = count - 1;
    while (b - a > 1) {
        uint32_t mid = a + (b - a) / 2;
        if (nodes[3 * mid] <= depth)
            a = mid;
        else
            b = mid;
    }
    float d0 = nodes[3 * a], d1 = nodes[3 * b];
    float f = (depth - d0) / (d1 - d0);
    for (int ch = 0; ch < 2; ch++) {
        float v0 = nodes[3 * a + 1 + ch], v1 = nodes[3 * b + 1 + ch];
        out[ch] = v0 + (v1 - v0) * f;
    }
}

void light_compressed_sample_diffuse(const struct light_compressed *c, const float tex[3],
                                     float out[2])
{
    out[0] = out[1] = 0.0f;
    if (!c->diffuse_columns)
        return;
    float tx, ty;
    int i = light_tex_node(tex[0], c->grid.n[0], &tx);
    int j = light_tex_node(tex[1], c->grid.n[1], &ty);
    float depth =
        fminf(fmaxf(tex[2] * (float)c->grid.n[2] - 0.5f, 0.0f), (float)(c->grid.n[2] - 1));
    float v00[2], v10[2], v01[2], v11[2];
    diffuse_column_at(c, i, j, depth, v00);
    diffuse_column_at(c, i + 1, j, depth, v10);
    diffuse_column_at(c, i, j + 1, depth, v01);
    diffuse_column_at(c, i + 1, j + 1, depth, v11);
    for (int ch = 0; ch < 2; ch++) {
        float r0 = v00[ch] + tx * (v10[ch] - v00[ch]);
        float r1 = v01[ch] + tx * (v11[ch] - v01[ch]);
        out[ch] = r0 + ty * (r1 - r0);
    }
}

size_t light_compressed_bytes(const struct light_compressed *c)
{
    size_t columns = (size_t)c->grid.n[0] * c->grid.n[1] * 2 * sizeof(uint32_t);
    return columns + c->node_count * 2 * sizeof(float) +
           (c->diffuse_columns ? columns + c->diffuse_node_count * 3 * sizeof(float) : 0);
}
