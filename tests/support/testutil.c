#include "testutil.h"

#include "session/effects.h"
#include "session/lightmaps.h"
#include "session/scene.h"
#include "session/stats.h"
#include "data/wrf_write.h"
#include "gpu/gpu.h"
#include "render/render.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char tmpdir[256];
static char pathbuf[4096];

const char *test_shared_data(const char *name)
{
    snprintf(pathbuf, sizeof(pathbuf), "%s/%s", ANVIL_SHARED_DATA, name);
    return pathbuf;
}

const char *test_fixture(const char *name)
{
    snprintf(pathbuf, sizeof(pathbuf), "%s/%s", ANVIL_TEST_DATA, name);
    return pathbuf;
}

static void remove_tmpdir(void)
{
    if (tmpdir[0]) {
        char cmd[300];
        snprintf(cmd, sizeof(cmd), "rm -rf '%s'", tmpdir);
        if (system(cmd) != 0)
            fprintf(stderr, "could not remove %s\n", tmpdir);
    }
}

const char *test_tmpdir(void)
{
    if (!tmpdir[0]) {
        snprintf(tmpdir, sizeof(tmpdir), "/tmp/anvil-test-XXXXXX");
        if (!mkdtemp(tmpdir)) {
            perror("mkdtemp");
            abort();
        }
        atexit(remove_tmpdir);
    }
    return tmpdir;
}

const char *test_tmp_path(const char *name)
{
    snprintf(pathbuf, sizeof(pathbuf), "%s/%s", test_tmpdir(), name);
    return pathbuf;
}

const char *test_write_file(const char *name, const char *text)
{
    const char *path = test_tmp_path(name);
    FILE *f = fopen(path, "w");
    if (!f) {
        perror(path);
        abort();
    }
    fputs(text, f);
    fclose(f);
    return path;
}

struct gpu_context *test_gl_context_or_skip(void)
{
    struct gpu_context *ctx = gpu_context_create(&(struct gpu_context_desc){.backend = "egl"});
    if (!ctx) {
        fprintf(stderr, "no OpenGL 4.5 context: skipping\n");
        exit(TEST_SKIP);
    }
    return ctx;
}

void test_config_from(struct config *cfg, const char **sets, int n)
{
    test_config_file(cfg, NULL, sets, n);
}

void test_config_file(struct config *cfg, const char *path, const char **sets, int n)
{
    config_defaults(cfg);
    if (path)
        assert_true(config_load(path, cfg));
    for (int i = 0; i < n; i++)
        assert_true(config_set(cfg, sets[i]));
    assert_true(config_validate(cfg));
}

void test_upload_scene(struct renderer *r, const struct config *cfg, struct ext_volume *vol)
{
    assert_true(scene_build_volume(cfg, vol));
    assert_true(renderer_set_volume(r, vol));
    assert_true(renderer_set_optics(r, &cfg->optics.params));
}

void test_scene_light(struct renderer *r, const struct config *cfg, const struct ext_volume *vol,
                      struct lightmaps *light, struct effects *e)
{
    const struct effects_context none = {0};
    struct effects_facts f;
    assert_true(effects_gather(cfg, vol, &none, &f));
    effects_decide(cfg, &f, e);
    assert_true(lightmaps_init(light, cfg));
    lightmaps_set_effects(light, e);
    assert_true(lightmaps_update(light, cfg, r, NULL));
}

void test_write_wrf_step(const char *path, const struct field_volume *in)
{
    struct wrf_writer *ww = wrf_writer_create(path, &in->grid, NULL);
    assert_non_null(ww);
    assert_true(wrf_writer_add(ww, in, "2000-01-01_00:00:00"));
    assert_true(wrf_writer_finish(ww));
}

void test_stretch_levels(struct ext_volume *vol)
{
    struct grid3 *g = &vol->grid;
    int nz = g->n[2];
    double h = nz * g->spacing[2], zc[GRID3_LEVELS_MAX];
    for (int k = 0; k < nz; k++) {
        double a = (double)k / nz, b = (double)(k + 1) / nz;
        zc[k] = g->origin[2] + 0.5 * (a * a + b * b) * h;
    }
    assert_true(grid3_set_levels(g, zc, nz, g->origin[2], g->origin[2] + h));
    assert_true(grid3_stretched(g));
}
