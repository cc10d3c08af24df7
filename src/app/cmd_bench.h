/*
 * app/cmd_bench: the commands about accuracy and its cost.  anvil reference renders the Monte
 * Carlo reference image of a config (bench/reference) with its per-pixel standard error.
 */
#ifndef ANVIL_APP_CMD_BENCH_H
#define ANVIL_APP_CMD_BENCH_H

/* anvil reference [CONFIG] -o FILE.pfm --spp N [--threads N] [--seed S] [--albedo A]
 * [--jitter] [--set PATH=VALUE]...  Writes FILE.pfm (mean radiance) and FILE.stderr.pfm
 * (standard error of each pixel's mean).  Returns an exit code of app.h. */
int cmd_reference(int argc, char **argv);

#endif
