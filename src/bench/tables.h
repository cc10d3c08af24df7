/*
 * bench/tables: what the benchmarks found, as text.  The markdown tables under docs/bench/
 * with the prose that says how they were measured, the Pareto verdicts, the CSV, and the
 * summaries the command echoes.  Pure formatting onto a stream the caller opens (a file, a
 * memory stream, stdout): no GL, no configs, no measuring, no file names.
 */
#ifndef ANVIL_BENCH_TABLES_H
#define ANVIL_BENCH_TABLES_H

#include <stdbool.h>
#include <stdio.h>

#include "bench/bench.h"
#include "bench/experiments.h"

/* The first line of a generated table: the command that makes it (RUN: "views" or
 * "quality"; QUICK: the CI-sized run). */
void bench_table_head(FILE *f, bool quick, const char *run);

/* ---- views -------------------------------------------------------------------------- */

/* The views table (views-table.md, after its head): N rows measured on SC with views of
 * W x H, medians of REPEATS frames, on DEVICE (gpu_renderer_name). */
void bench_write_views_table(FILE *f, const struct bench_scene *sc,
                             const struct bench_views_row *rows, int n, int w, int h, int repeats,
                             const char *device);

/* The same rows in a few lines, for the terminal. */
void bench_write_views_summary(FILE *f, const struct bench_views_row *rows, int n,
                               const char *device);

/* ---- quality ------------------------------------------------------------------------ */

/* Appends the results of one scene as CSV rows (HEADER: write the header line first). */
void bench_write_csv(FILE *f, const char *scene, const struct bench_result *res, int n,
                     bool header);

/* A markdown table of one scene's results. */
void bench_write_markdown(FILE *f, const char *scene, const struct bench_result *res, int n);

/* The Pareto verdict on scene S's default, against Monte Carlo or (SELF) against the converged
 * renderer: on the front, or beaten by which settings.  Nothing when S has no default. */
void bench_write_verdict(FILE *f, const struct bench_scene_results *s, bool self);

/* The defaults are one setting for every scene: a setting beats them across the N scenes S
 * when, the same on each, it is no slower and no worse on every scene and faster or better on
 * one (each beyond the noise, bench_beats).  Settings missing from a scene (a knob that
 * scene's defaults make moot) are left out.  Nothing for fewer than two scenes. */
void bench_write_verdict_across(FILE *f, const struct bench_scene_results *s, int n, bool self);

/* accuracy.csv: every scene's rows under one header. */
void bench_write_accuracy_csv(FILE *f, const struct bench_scene_results *s, int n);

/* accuracy-table.md after its head: how it was measured on DEVICE with SPP reference samples
 * per pixel (64 times that for the sphere), each scene's σ and table, then the verdicts
 * against Monte Carlo and against the converged renderer. */
void bench_write_accuracy_table(FILE *f, const struct bench_scene_results *s, int n,
                                const char *device, int spp);

/* ---- experiments -------------------------------------------------------------------- */

/* angles-table.md after its head: the layer seen from every direction (the picture's mean
 * over Monte Carlo's, and Monte Carlo's means), then the wall under every sun. */
void bench_write_angles_table(FILE *f, const struct bench_angles *a, const char *device, int spp);

#endif
