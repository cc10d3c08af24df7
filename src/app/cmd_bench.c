/* anvil bench: the command line of bench/run.h (views, quality sweep, experiments). */
#include <getopt.h>
#include <stdio.h>
#include <string.h>

#include "app/app.h"
#include "app/cmd_bench.h"
#include "bench/run.h"
#include "common/log.h"

static int usage(FILE *out)
{
    fprintf(out,
            "usage: anvil bench [--quick] [--views-only | --quality-only | --movie-only |\n"
            "                   --scale-only | --gpu | --cluster-only | --load-only |\n"
            "                   --playback-only | --volume-only]\n"
            "                   [-o DIR]\n"
            "                   [--cache DIR] [--images DIR]\n"
            "                   [--configs DIR] [--displays DIR] [--spp N]\n"
            "                   [--scene sphere|storm|katrina]...\n"
            "                   [--paraview] [--quiet]\n"
            "What accuracy costs in time (docs/accuracy.md):\n"
            "  views    frame cost of 1, 2, 8 and 12 views sharing one light map against the\n"
            "           same views each rebuilding it\n"
            "  quality  each quality knob swept around the defaults on named scenes: GPU ms per\n"
            "           light build and per view, error against the Monte Carlo reference;\n"
            "           then a uniform cloud layer seen from 16 directions and a uniform\n"
            "           wall under 4 suns against Monte Carlo\n"
            "  movie    frames per second of the default storm's movie, drawn only and\n"
            "           written through the encoder (movie-table.md)\n"
            "  scale    the storm, its box left empty and the storm on a 500 x 500 x 100 grid:\n"
            "           views with and without empty-space skipping, what their rays did,\n"
            "           the light build (scale-table.md)\n"
            "  cluster  cave4 and cave6 drawn by 1, 2 and 4 ranks through mpirun: ms a frame\n"
            "           and the collectives' share (cluster-table.md; left out without MPI)\n"
            "  --load-only  a time step of a 500 x 500 x 100 WRF file (written to\n"
            "           $TMPDIR or /tmp, then removed) loaded to extinction against the\n"
            "           plain NetCDF read of its variables, side by side, with the peak\n"
            "           memory of each (load-table.md; not part of the default run)\n"
            "  --playback-only  a 500 x 500 x 100 WRF series (written, then removed) played\n"
            "           as anvil run plays it, with the next step readied between frames and\n"
            "           with each step change uploading and building in its frame, side by\n"
            "           side: step rate, frame times, stalls (playback-table.md; not part of\n"
            "           the default run)\n"
            "  --volume-only  the layer from 16 directions and the wall under 4 suns with\n"
            "           the 3-D diffuse light volume (effects.multiple = \"volume\"), drawn\n"
            "           on the CPU, against Monte Carlo; its build time beside the light\n"
            "           map's CPU build (volume-table.md; not part of the default run)\n"
            "  --gpu    the storm on 500 x 500 x 100 voxels as an HMD frame (2 x 1440 x 1600)\n"
            "           and as displays/cave4.cfg (8 x 1280 x 1024) sharing one light map: GPU\n"
            "           ms per frame, the rebuild, fetches per second against the device's\n"
            "           peak (gpu-table.md); minutes on a GPU, far longer on a CPU rasteriser\n"
            "  -o DIR         where views.md, accuracy.csv, accuracy-table.md, accuracy.png\n"
            "                 and angles-table.md go (default docs/bench)\n"
            "  --cache DIR    Monte Carlo references are kept here (default: bench-cache\n"
            "                 beside the anvil binary)\n"
            "  --images DIR   also write each swept scene's reference (NAME-reference.pfm,\n"
            "                 NAME-reference.stderr.pfm) and the pictures it is compared\n"
            "                 with: the default (NAME-default.pfm) and the 3-D diffusion\n"
            "                 tier (NAME-volume.pfm)\n"
            "  --configs DIR  sphere.cfg and katrina.cfg, which names the WRF sample relative\n"
            "                 to itself (default: the source tree's configs/, reading\n"
            "                 ../shared/data beside the tree); a scene without its data file\n"
            "                 is left out with a warning\n"
            "  --displays DIR cave4.cfg for --gpu (default: the source tree's displays/)\n"
            "  --spp N        reference samples per pixel (default 256, --quick 32; the\n"
            "                 sphere gets 64 times as many)\n"
            "  --quick        small scenes and images, one repeat: a CI-sized run\n"
            "  --paraview     also time ParaView's shadowed volume rendering of the same\n"
            "                 volume and views (src/bench/paraview_views.py through pvbatch,\n"
            "                 under xvfb-run without a display) into views-paraview.md;\n"
            "                 skipped with \"ParaView not available\" without pvbatch on PATH\n");
    return EXIT_USAGE;
}

/* Fills O from the command line; -1 for --help, else an exit code. */
static int parse(int argc, char **argv, struct bench_options *o)
{
    static const struct option longopts[] = {
        {"quick", no_argument, NULL, 'Q'},         {"views-only", no_argument, NULL, 'V'},
        {"quality-only", no_argument, NULL, 'A'},  {"output", required_argument, NULL, 'o'},
        {"cache", required_argument, NULL, 'c'},   {"spp", required_argument, NULL, 'n'},
        {"scene", required_argument, NULL, 's'},   {"quiet", no_argument, NULL, 'q'},
        {"paraview", no_argument, NULL, 'P'},      {"configs", required_argument, NULL, 'C'},
        {"movie-only", no_argument, NULL, 'M'},    {"help", no_argument, NULL, 'h'},
        {"scale-only", no_argument, NULL, 'S'},    {"gpu", no_argument, NULL, 'G'},
        {"cluster-only", no_argument, NULL, 'L'},  {"load-only", no_argument, NULL, 'D'},
        {"playback-only", no_argument, NULL, 'Y'}, {"volume-only", no_argument, NULL, 'W'},
        {"images", required_argument, NULL, 'I'},  {"displays", required_argument, NULL, 'R'},
        {NULL, 0, NULL, 0},
    };
    bench_options_defaults(o);
    o->out = "docs/bench";
    o->configs = ANVIL_SOURCE_DIR "/configs";
    o->displays = ANVIL_SOURCE_DIR "/displays";
    o->paraview_script = ANVIL_SOURCE_DIR "/src/bench/paraview_views.py";
    o->report = stdout;
    optind = 1;
    int c, only = 0;
    long spp;
    while ((c = getopt_long(argc, argv, "o:qh", longopts, NULL)) != -1) {
        switch (c) {
        case 'Q':
            o->quick = true;
            break;
        case 'V':
            o->quality = o->movie = o->scale = o->cluster = false;
            only++;
            break;
        case 'A':
            o->views = o->movie = o->scale = o->cluster = false;
            only++;
            break;
        case 'M':
            o->views = o->quality = o->scale = o->cluster = false;
            only++;
            break;
        case 'S':
            o->views = o->quality = o->movie = o->cluster = false;
            only++;
            break;
        case 'L':
            o->views = o->quality = o->movie = o->scale = false;
            only++;
            break;
        case 'D':
            o->views = o->quality = o->movie = o->scale = o->cluster = false;
            o->load = true;
            only++;
            break;
        case 'Y':
            o->views = o->quality = o->movie = o->scale = o->cluster = false;
            o->playback = true;
            only++;
            break;
        case 'W':
            o->views = o->quality = o->movie = o->scale = o->cluster = false;
            o->volume = true;
            only++;
            break;
        case 'G':
            o->views = o->quality = o->movie = o->scale = o->cluster = false;
            o->device = true;
            only++;
            break;
        case 'o':
            o->out = optarg;
            break;
        case 'c':
            o->cache = optarg;
            break;
        case 'I':
            o->images = optarg;
            break;
        case 'C':
            o->configs = optarg;
            break;
        case 'R':
            o->displays = optarg;
            break;
        case 'P':
            o->paraview = true;
            break;
        case 'q':
            log_set_level(LOG_ERROR);
            break;
        case 'h':
            return -1;
        case 'n':
            if (!app_option_long("bench", "--spp", optarg, 2, 1L << 20, &spp))
                return EXIT_BAD_INPUT;
            o->spp = (int)spp;
            break;
        case 's':
            if (!bench_scene_known(optarg)) {
                log_error("bench: --scene: expected sphere, storm or katrina, got \"%s\"", optarg);
                return EXIT_BAD_INPUT;
            }
            if (o->n_scenes < BENCH_MAX_SCENES)
                o->scenes[o->n_scenes++] = optarg;
            break;
        default:
            return EXIT_USAGE;
        }
    }
    if (optind < argc) {
        log_error("bench: unexpected argument \"%s\"", argv[optind]);
        return EXIT_USAGE;
    }
    if (only > 1) {
        log_error("bench: --views-only, --quality-only, --movie-only, --scale-only, "
                  "--cluster-only, --load-only, --playback-only, --volume-only and --gpu "
                  "exclude each other");
        return EXIT_USAGE;
    }
    if (o->paraview && !o->views) {
        log_error("bench: --paraview compares the views benchmark; it excludes --quality-only");
        return EXIT_USAGE;
    }
    if (o->images && !o->quality) {
        log_error("bench: --images writes the quality sweep's pictures; it needs the quality "
                  "benchmark (no --views-only, --movie-only, ...)");
        return EXIT_USAGE;
    }
    return EXIT_OK;
}

int cmd_bench(int argc, char **argv)
{
    struct bench_options o;
    int rc = parse(argc, argv, &o);
    if (rc < 0) {
        usage(stdout);
        return EXIT_OK;
    }
    if (rc == EXIT_USAGE)
        return usage(stderr);
    if (rc != EXIT_OK)
        return rc;
    enum bench_status status = bench_run(&o);
    return status == BENCH_DONE ? EXIT_OK : status == BENCH_NO_GPU ? EXIT_NO_GPU : EXIT_FAILED;
}
