/*
 * Test support shared by every test program: where the sample data and fixtures are, a
 * per-test temporary folder, and the GL skip convention (exit 77 when no context).
 * Include <cmocka.h> through this header.
 */
#ifndef ANVIL_TESTUTIL_H
#define ANVIL_TESTUTIL_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#define TEST_SKIP 77

/* Path of a file under ../shared/data (e.g. "wrf/katrina_2005_mercator_wsm3.nc").  Returns a
 * static buffer overwritten by the next call. */
const char *test_shared_data(const char *name);

/* Path of a fixture under tests/data.  Static buffer as above. */
const char *test_fixture(const char *name);

/* A fresh empty folder for this test program (created on first call, removed at exit). */
const char *test_tmpdir(void);

/* Path NAME inside test_tmpdir().  Static buffer as above. */
const char *test_tmp_path(const char *name);

/* Writes TEXT to a file NAME in the temporary folder and returns its path (static buffer). */
const char *test_write_file(const char *name, const char *text);



struct gpu_context;
struct config;
struct renderer;
struct ext_volume;
struct field_volume;
struct lightmaps;
struct effects;

/* VOL's levels moved onto uneven ones in the same box (the model's own levels of a WRF file,
 * data/volume.h): faces at (k / n)^2 of the height, thin at the bottom, thick aloft. */
void test_stretch_levels(struct ext_volume *vol);

/* Writes IN as a one-step WRF file (time 2000-01-01_00:00:00) at PATH (asserts). */
void test_write_wrf_step(const char *path, const struct field_volume *in);

/* CFG = the defaults with the N "path=value" overrides SETS applied, validated (asserts). */
void test_config_from(struct config *cfg, const char **sets, int n);

/* The same over the config file PATH (NULL: the defaults alone). */
void test_config_file(struct config *cfg, const char *path, const char **sets, int n);

/* Builds CFG's volume into VOL (the caller finishes it) and uploads it and the optics to R. */
void test_upload_scene(struct renderer *r, const struct config *cfg, struct ext_volume *vol);

/* LIGHT made for CFG and built for R's volume VOL, with the effects E that CFG decides for VOL
 * as a program does (effects_gather, no display, no time steps, views not known); the caller
 * finishes LIGHT. */
void test_scene_light(struct renderer *r, const struct config *cfg, const struct ext_volume *vol,
                      struct lightmaps *light, struct effects *e);

/* A headless OpenGL 4.5 context, or exit(TEST_SKIP) with a message when none can be made. */
struct gpu_context *test_gl_context_or_skip(void);
#endif
