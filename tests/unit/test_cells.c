/*
 * The macro cells' clear distances on the CPU (render_cells_distance_cpu): each clear level-0
 * cell's Chebyshev distance to the nearest occupied cell, capped, against a brute-force search,
 * and what a pair of volumes' cells (the larger of the two, cell by cell) makes of them.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "render/render.h"

/* A small deterministic generator (the tests' own; no dependence on the C library's rand). */
static unsigned next_random(unsigned *state)
{
    *state = *state * 1664525u + 1013904223u;
    return *state >> 8;
}

/* Level 0 of LAYOUT's cells with about one cell in ONE_IN occupied (by positive maxima), the
 * coarser levels 0; SEED picks them. */
static float *random_cells(const struct render_cells *layout, unsigned one_in, unsigned seed)
{
    float *v = calloc(layout->count, sizeof(float));
    assert_non_null(v);
    const int *d = layout->dims[0];
    size_t n = (size_t)d[0] * d[1] * d[2];
    for (size_t i = 0; i < n; i++)
        if (one_in && next_random(&seed) % one_in == 0)
            v[i] = 0.5f + (float)(next_random(&seed) % 1000);
    return v;
}

/* The distance the cells must hold at (x, y, z): the smallest max(|dx|, |dy|, |dz|) to one of
 * the COUNT occupied cells AT (x, y, z triples), at most RENDER_CELL_DISTANCE_MAX + 1, by
 * looking at every one. */
static int brute_distance(const int *at, size_t count, int x, int y, int z)
{
    int best = RENDER_CELL_DISTANCE_MAX + 1;
    for (size_t o = 0; o < count; o++) {
        int e = abs(at[3 * o] - x);
        e = abs(at[3 * o + 1] - y) > e ? abs(at[3 * o + 1] - y) : e;
        e = abs(at[3 * o + 2] - z) > e ? abs(at[3 * o + 2] - z) : e;
        best = e < best ? e : best;
    }
    return best;
}

/* Every clear cell holds −(its distance), every occupied cell its maximum, and the coarser
 * levels are untouched. */
static void check_distances(const struct render_cells *layout, const float *original,
                            const float *got)
{
    const int *d = layout->dims[0];
    size_t n = (size_t)d[0] * d[1] * d[2], count = 0;
    int *at = malloc(3 * n * sizeof(int));
    assert_non_null(at);
    for (int z = 0; z < d[2]; z++)
        for (int y = 0; y < d[1]; y++)
            for (int x = 0; x < d[0]; x++)
                if (original[x + (size_t)d[0] * (y + (size_t)d[1] * z)] > 0.0f) {
                    at[3 * count] = x;
                    at[3 * count + 1] = y;
                    at[3 * count + 2] = z;
                    count++;
                }
    for (int z = 0; z < d[2]; z++)
        for (int y = 0; y < d[1]; y++)
            for (int x = 0; x < d[0]; x++) {
                size_t i = x + (size_t)d[0] * (y + (size_t)d[1] * z);
                if (original[i] > 0.0f) {
                    assert_true(got[i] == original[i]);
                    continue;
                }
                int want = brute_distance(at, count, x, y, z);
                if (got[i] != -(float)want)
                    fail_msg("cell (%d, %d, %d): %g, expected %d", x, y, z, got[i], -want);
            }
    free(at);
    for (size_t i = n; i < layout->count; i++)
        assert_true(got[i] == original[i]);
}

/* Sparse cells in a grid wider than the cap (distances up to the cap and beyond it), denser
 * ones, a single cell in a corner, and none at all. */
static void test_distances_are_chebyshev(void **state)
{
    (void)state;
    const int n[3] = {160, 124, 60}; /* 40 x 31 x 15 cells */
    struct render_cells layout;
    render_cells_layout(n, RENDER_CELL_VOXELS, &layout);
    const unsigned densities[] = {2000, 40, 0};
    for (size_t k = 0; k < sizeof(densities) / sizeof(densities[0]); k++) {
        float *original = random_cells(&layout, densities[k], 7u + (unsigned)k);
        if (densities[k] == 0)
            original[0] = 3.0f; /* one occupied cell, in the corner */
        float *got = malloc(layout.count * sizeof(float));
        assert_non_null(got);
        memcpy(got, original, layout.count * sizeof(float));
        render_cells_distance_cpu(&layout, got);
        check_distances(&layout, original, got);
        /* The sparse and the single cell reach the cap; the dense ones are near. */
        float lowest = 0.0f;
        for (size_t i = 0; i < layout.count; i++)
            lowest = got[i] < lowest ? got[i] : lowest;
        print_message("one cell in %u occupied: the farthest clear cell %g cells away\n",
                      densities[k], -lowest);
        if (densities[k] != 40)
            assert_true(lowest == -(float)(RENDER_CELL_DISTANCE_MAX + 1));
        free(original);
        free(got);
    }
    /* Nothing occupied: every cell at the cap. */
    float *none = calloc(layout.count, sizeof(float));
    assert_non_null(none);
    render_cells_distance_cpu(&layout, none);
    const int *d = layout.dims[0];
    for (size_t i = 0; i < (size_t)d[0] * d[1] * d[2]; i++)
        assert_true(none[i] == -(float)(RENDER_CELL_DISTANCE_MAX + 1));
    free(none);
}

/* The cells of a pair of volumes are the larger of each's, cell by cell (render_cells_max):
 * for the distances that is the smaller one, the distance to the nearer occupied cell of
 * either, which is what the union's own distances are. */
static void test_pair_of_distances_is_the_union(void **state)
{
    (void)state;
    const int n[3] = {96, 80, 44};
    struct render_cells layout;
    render_cells_layout(n, RENDER_CELL_VOXELS, &layout);
    float *a = random_cells(&layout, 300, 11u), *b = random_cells(&layout, 300, 12u);
    float *both = malloc(layout.count * sizeof(float));
    assert_non_null(both);
    for (size_t i = 0; i < layout.count; i++)
        both[i] = a[i] > b[i] ? a[i] : b[i];
    render_cells_distance_cpu(&layout, a);
    render_cells_distance_cpu(&layout, b);
    render_cells_distance_cpu(&layout, both);
    for (size_t i = 0; i < layout.count; i++) {
        float m = a[i] > b[i] ? a[i] : b[i];
        if (m != both[i])
            fail_msg("cell %zu: the larger of the two %g, the union's %g", i, m, both[i]);
    }
    free(a);
    free(b);
    free(both);
}

/* Grids of every shape, down to one cell along an axis, at densities from every cell to
 * almost none: each the brute force's distances. */
static void test_distances_on_many_grids(void **state)
{
    (void)state;
    unsigned seed = 99u;
    const unsigned densities[] = {1, 3, 20, 200, 3000, 100000};
    for (int run = 0; run < 300; run++) {
        int n[3];
        for (int a = 0; a < 3; a++)
            n[a] = 1 + (int)(next_random(&seed) % (a == 2 ? 60u : 90u));
        struct render_cells layout;
        render_cells_layout(n, RENDER_CELL_VOXELS, &layout);
        float *original = random_cells(&layout, densities[run % 6], seed + (unsigned)run);
        float *got = malloc(layout.count * sizeof(float));
        assert_non_null(got);
        memcpy(got, original, layout.count * sizeof(float));
        render_cells_distance_cpu(&layout, got);
        check_distances(&layout, original, got);
        free(original);
        free(got);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_distances_are_chebyshev),
        cmocka_unit_test(test_pair_of_distances_is_the_union),
        cmocka_unit_test(test_distances_on_many_grids),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
