/* Pictures that must not change: tests/data/golden/cases.sh renders the default storm,
 * Katrina, the four-wall CAVE, the Null HMD, desktop stereo, the menu and a blended playback
 * frame headless; every PFM kept beside it must come out the same within 1e-5 relative. */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "testutil.h"

#include "gpu/gpu.h"
#include "render/image.h"

#define TOLERANCE 1e-5

static char golden_dir[1024];
static char out_dir[1024];
static int compared;

/* Largest relative difference of any channel (alpha included) of A and B. */
static double max_relative(const struct image *a, const struct image *b, int *worst)
{
    double worst_rel = 0.0;
    size_t n = (size_t)a->width * (size_t)a->height * 4;
    for (size_t i = 0; i < n; i++) {
        double x = a->rgba[i], y = b->rgba[i];
        double scale = fmax(fabs(x), fabs(y));
        double rel = scale > 0.0 ? fabs(x - y) / scale : 0.0;
        if (!(rel <= worst_rel)) { /* NaN counts as the worst */
            worst_rel = isnan(rel) ? INFINITY : rel;
            *worst = (int)(i / 4);
        }
    }
    return worst_rel;
}

static void compare_file(const char *rel)
{
    char want_path[2048], got_path[2048];
    snprintf(want_path, sizeof(want_path), "%s/%s", golden_dir, rel);
    snprintf(got_path, sizeof(got_path), "%s/%s", out_dir, rel);
    struct image want = {0}, got = {0};
    assert_true(image_read_pfm(want_path, &want));
    if (!image_read_pfm(got_path, &got))
        fail_msg("%s was not written", rel);
    if (want.width != got.width || want.height != got.height)
        fail_msg("%s: %dx%d, expected %dx%d", rel, got.width, got.height, want.width,
                 want.height);
    int worst = -1;
    double rel_diff = max_relative(&want, &got, &worst);
    printf("%-24s %4dx%-4d max relative difference %.3g\n", rel, want.width, want.height,
           rel_diff);
    if (!(rel_diff <= TOLERANCE))
        fail_msg("%s: pixel (%d, %d) differs by %.3g relative (at most %g)", rel,
                 worst % want.width, worst / want.width, rel_diff, TOLERANCE);
    compared++;
    image_finish(&want);
    image_finish(&got);
}

/* Every *.pfm under golden_dir/SUB. */
static void compare_tree(const char *sub)
{
    char dir[2048];
    snprintf(dir, sizeof(dir), "%s%s%s", golden_dir, sub[0] ? "/" : "", sub);
    DIR *d = opendir(dir);
    assert_non_null(d);
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        if (e->d_name[0] == '.')
            continue;
        char rel[1024], full[3072];
        snprintf(rel, sizeof(rel), "%s%s%s", sub, sub[0] ? "/" : "", e->d_name);
        snprintf(full, sizeof(full), "%s/%s", golden_dir, rel);
        struct stat st;
        assert_int_equal(stat(full, &st), 0);
        size_t len = strlen(e->d_name);
        if (S_ISDIR(st.st_mode))
            compare_tree(rel);
        else if (len > 4 && strcmp(e->d_name + len - 4, ".pfm") == 0)
            compare_file(rel);
    }
    closedir(d);
}

static void test_pictures_unchanged(void **state)
{
    (void)state;
    const char *anvil = getenv("ANVIL_BIN");
    assert_non_null(anvil);
    snprintf(golden_dir, sizeof(golden_dir), "%s/golden", ANVIL_TEST_DATA);
    snprintf(out_dir, sizeof(out_dir), "%s/out", test_tmpdir());
    char cmd[4096];
    snprintf(cmd, sizeof(cmd), "sh '%s/cases.sh' '%s' '%s' '%s'", golden_dir, anvil,
             ANVIL_SOURCE_DIR, out_dir);
    assert_int_equal(system(cmd), 0);
    compare_tree("");
    assert_true(compared >= 18); /* every case above wrote its files */
}

int main(void)
{
    gpu_context_destroy(test_gl_context_or_skip());
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pictures_unchanged),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
