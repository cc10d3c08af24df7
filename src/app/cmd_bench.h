/*
 * app/cmd_bench: the commands about accuracy and its cost.  anvil reference renders the Monte
 * Carlo reference image of a config (reference/) with its per-pixel standard error;
 * anvil effects says what a config simulates and why; anvil bench measures what accuracy
 * costs in time.
 */
#ifndef ANVIL_APP_CMD_BENCH_H
#define ANVIL_APP_CMD_BENCH_H

/* anvil reference [CONFIG] -o FILE.pfm --spp N [--threads N] [--seed S] [--albedo A]
 * [--jitter] [--set PATH=VALUE]...  Writes FILE.pfm (mean radiance) and FILE.stderr.pfm
 * (standard error of each pixel's mean).  Returns an exit code of app.h. */
int cmd_reference(int argc, char **argv);

/* anvil effects [CONFIG] [--display DISPLAY.cfg] [--run] [--set PATH=VALUE]...  Prints each
 * effect's decision and its reason (session/effects.h). */
int cmd_effects(int argc, char **argv);

/* anvil bench [--quick] [--views-only | --quality-only] [-o DIR] [--cache DIR] [--configs DIR]
 * [--spp N] [--scene NAME]... [--paraview]  Frame cost of many views with one light map
 * against a build per view, and the quality sweep: milliseconds and error against the Monte
 * Carlo reference for each quality knob on named scenes; writes CSV, markdown and PNG plots
 * into DIR (bench/run.h). */
int cmd_bench(int argc, char **argv);

#endif
