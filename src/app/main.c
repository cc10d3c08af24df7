/* anvil: immersive multi-view stereo volume rendering of weather simulations. */
#include <stdio.h>
#include <string.h>

#include "app/app.h"
#include "app/cmd_bench.h"
#include "app/cmd_data.h"
#include "cluster/cluster.h"
#include "common/fatal.h"
#include "common/log.h"
#include "config/config.h"
#include "config/display_config.h"
#include "display/display.h"

struct command {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *summary;
};

static const struct command commands[] = {
    {"render", cmd_render, "render views headless (EGL) to PNG or PFM files"},
    {"run", cmd_run, "open a window: orbit, zoom, move the sun"},
    {"trackers", cmd_trackers, "a display's tracked head and wand, live, in room coordinates"},
    {"probe", cmd_probe, "the values at one point: mass ratios, temperature, wind, light"},
    {"info", cmd_info, "describe WRF, CM1, CF or extinction files, or a folder of Isabel bricks"},
    {"synth", cmd_synth, "write the procedural storm as a WRF-, CM1- or CF-convention NetCDF series"},
    {"convert", cmd_convert, "precompute ice and water extinction volumes into a NetCDF file"},
    {"reference", cmd_reference, "Monte Carlo reference image and its standard error (CPU)"},
    {"effects", cmd_effects, "which effects a config simulates, and why"},
    {"bench", cmd_bench, "what accuracy costs in time: views and quality benchmarks"},
};

static void usage(FILE *out)
{
    fprintf(out, "usage: anvil [--quiet] COMMAND [ARGS]\n"
                 "       anvil --help | --version | --config-reference\n\ncommands:\n");
    for (size_t i = 0; i < sizeof(commands) / sizeof(commands[0]); i++)
        fprintf(out, "  %-10s %s\n", commands[i].name, commands[i].summary);
    fprintf(out, "\nanvil COMMAND --help shows a command's options.  Exit codes: 0 done, 1 bad "
                 "input (config, data, option value), 2 usage, 3 no OpenGL 4.5 context, "
                 "4 other failure, 130/143 interrupted (SIGINT/SIGTERM).\n");
}

int main(int argc, char **argv)
{
    fatal_install();
    int i = 1;
    for (; i < argc && argv[i][0] == '-'; i++) {
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            usage(stdout);
            return EXIT_OK;
        } else if (strcmp(argv[i], "--version") == 0) {
            printf("anvil %s\n", ANVIL_VERSION);
            /* What the build found of its optional parts. */
            printf("clusters (MPI): %s\nOpenXR headsets: %s\n", cluster_available() ? "yes" : "no",
                   display_type_available(DISPLAY_TYPE_OPENXR) ? "yes" : "no");
            return EXIT_OK;
        } else if (strcmp(argv[i], "--quiet") == 0 || strcmp(argv[i], "-q") == 0) {
            log_set_level(LOG_ERROR);
        } else if (strcmp(argv[i], "--verbose") == 0 || strcmp(argv[i], "-v") == 0) {
            log_set_level(LOG_DEBUG);
        } else if (strcmp(argv[i], "--config-reference") == 0) {
            /* scene settings, then display settings (docs/config-reference.md) */
            config_write_reference(stdout);
            printf("\n");
            display_config_write_reference(stdout);
            return EXIT_OK;
        } else {
            fprintf(stderr, "anvil: unknown option %s\n", argv[i]);
            usage(stderr);
            return EXIT_USAGE;
        }
    }
    if (i >= argc) {
        usage(stderr);
        return EXIT_USAGE;
    }
    for (size_t c = 0; c < sizeof(commands) / sizeof(commands[0]); c++) {
        if (strcmp(argv[i], commands[c].name) == 0) {
            /* Under mpirun each rank runs the command; the walls are shared out among them. */
            if (!cluster_init(&argc, &argv))
                return EXIT_FAILED;
            int rc = commands[c].run(argc - i, argv + i);
            cluster_finish();
            fatal_exiting(rc); /* the libraries' exit handlers run after this */
            return rc;
        }
    }
    fprintf(stderr, "anvil: unknown command \"%s\"\n", argv[i]);
    usage(stderr);
    return EXIT_USAGE;
}
