/* Node compression of visibility functions (Nes §5.3.4, Lokovic-Veach) and their lookup. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "light/light.h"

static void emit(float *out, int *m, double depth, double value)
{
    out[2 * *m] = (float)depth;
    out[2 * *m + 1] = (float)value;
    (*m)++;
}

static double clampd(double x, double lo, double hi)
{
    return x < lo ? lo : x > hi ? hi : x;
}

int light_compress_column(const float *depth, const float *value, int count, double epsilon,
                          float *out)
{
    if (!(epsilon >= 0.0) || !isfinite(epsilon)) {
        log_error("light map compression: epsilon %g must be finite and >= 0", epsilon);
        return -1;
    }
    for (int c = 0; c < count; c++) {
        if (!isfinite(depth[c]) || !isfinite(value[c]) || (c > 0 && depth[c] < depth[c - 1])) {
            log_error("light map compression: sample %d is not finite or its depth decreases", c);
            return -1;
        }
    }
    if (count <= 0)
        return 0;

    int m = 0;
    double pd = depth[0], pv = value[0]; /* the current segment's start node */
    emit(out, &m, pd, pv);
    double lo = -INFINITY, hi = INFINITY; /* feasible slopes from the node */
    int members = 0;                      /* samples after the node in the segment */

    for (int c = 1; c < count; c++) {
        double dc = depth[c], vc = value[c];
        if (members > 0) {
            double dd = dc - pd; /* > 0: members lie deeper than the node, depths sorted */
            double slo = fmax(lo, (vc - epsilon - pv) / dd); /* Nes eq. 5.15 */
            double shi = fmin(hi, (vc + epsilon - pv) / dd); /* Nes eq. 5.14 */
            if (slo <= shi) {
                lo = slo, hi = shi; /* the segment passes every hoop so far */
                members++;
                continue;
            }
            /* Sample c cannot join: end the segment at the previous sample, on a slope every
             * member accepts (the one nearest the sample's own slope), so all members stay
             * within epsilon (Lokovic-Veach; Nes eq. 5.16-5.17 are the hoops). */
            double dp = depth[c - 1];
            double s = clampd((value[c - 1] - pv) / (dp - pd), lo, hi);
            if (m == 1 && lo <= 0.0 && hi >= 0.0) {
                /* A flat start: the next node alone stands for it, as lookups clamp to the
                 * first node's value before it. */
                s = 0.0;
                m = 0;
            }
            pv = pv + s * (dp - pd);
            pd = dp;
            emit(out, &m, pd, pv);
            lo = -INFINITY, hi = INFINITY;
            members = 0;
        }
        double dd = dc - pd;
        if (dd <= 0.0) {
            /* Same depth as the node: merge when within epsilon, else a step (two nodes at one
             * depth).  Never divides by the zero depth difference. */
            if (fabs(vc - pv) > epsilon) {
                pv = vc;
                emit(out, &m, pd, pv);
            }
            continue;
        }
        lo = (vc - epsilon - pv) / dd;
        hi = (vc + epsilon - pv) / dd;
        members = 1;
    }
    /* A flat tail needs no closing node: lookups clamp to the last node's value after it. */
    if (members > 0 && !(lo <= 0.0 && hi >= 0.0)) {
        double dl = depth[count - 1];
        double s = clampd((value[count - 1] - pv) / (dl - pd), lo, hi);
        emit(out, &m, dl, pv + s * (dl - pd));
    }
    return m;
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
    memset(c, 0, sizeof(*c));
}

bool light_compressed_build(const struct light_map *map, double epsilon,
                            struct light_compressed *out)
{
    memset(out, 0, sizeof(*out));
    out->grid = map->grid;
    out->epsilon = epsilon;
    const int n0 = map->grid.n[0], n1 = map->grid.n[1], n2 = map->grid.n[2];
    size_t ncol = (size_t)n0 * n1;
    size_t cap = ncol * 4; /* grown on demand; smooth maps need a few nodes per column */
    float *depth = malloc((size_t)n2 * sizeof(float));
    float *value = malloc((size_t)n2 * sizeof(float));
    float *tmp = malloc((size_t)n2 * 2 * sizeof(float));
    out->columns = malloc(ncol * 2 * sizeof(uint32_t));
    out->nodes = malloc(cap * 2 * sizeof(float));
    if (!depth || !value || !tmp || !out->columns || !out->nodes) {
        log_error("light map compression: out of memory for %d x %d columns", n0, n1);
        goto error;
    }
    for (int k = 0; k < n2; k++)
        depth[k] = (float)k;

    for (int j = 0; j < n1; j++) {
        for (int i = 0; i < n0; i++) {
            for (int k = 0; k < n2; k++)
                value[k] = light_map_node(map, i, j, k);
            int m = light_compress_column(depth, value, n2, epsilon, tmp);
            if (m < 0)
                goto error;
            if (out->node_count + (size_t)m > UINT32_MAX) {
                log_error("light map compression: more than 2^32 nodes");
                goto error;
            }
            if (out->node_count + (size_t)m > cap) {
                while (out->node_count + (size_t)m > cap)
                    cap *= 2;
                float *grown = realloc(out->nodes, cap * 2 * sizeof(float));
                if (!grown) {
                    log_error("light map compression: out of memory for %zu nodes", cap);
                    goto error;
                }
                out->nodes = grown;
            }
            size_t c = (size_t)i + (size_t)n0 * j;
            out->columns[2 * c] = (uint32_t)out->node_count;
            out->columns[2 * c + 1] = (uint32_t)m;
            memcpy(out->nodes + 2 * out->node_count, tmp, (size_t)m * 2 * sizeof(float));
            out->node_count += (size_t)m;
        }
    }
    float *fit = realloc(out->nodes, (out->node_count ? out->node_count : 1) * 2 * sizeof(float));
    if (fit)
        out->nodes = fit;
    free(depth);
    free(value);
    free(tmp);
    return true;

error:
    free(depth);
    free(value);
    free(tmp);
    light_compressed_finish(out);
    return false;
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

size_t light_compressed_bytes(const struct light_compressed *c)
{
    return (size_t)c->grid.n[0] * c->grid.n[1] * 2 * sizeof(uint32_t) +
           c->node_count * 2 * sizeof(float);
}
