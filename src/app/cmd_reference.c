/* anvil reference: the Monte Carlo reference image of a config and its standard error. */
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/app.h"
#include "app/cmd_bench.h"
#include "common/log.h"
#include "config/config.h"
#include "render/image.h"
#include "session/output.h"
#include "session/scene.h"
#include "session/traced.h"

#define MAX_SETS 64

struct reference_options {
    const char *config;
    char **args; /* CONFIG, FILES... (app_load_scene) */
    int n_args;
    const char *output;
    char *sets[MAX_SETS];
    int n_sets;
    long spp, threads;
    unsigned long long seed;
    double albedo;
    bool jitter;
};

static int usage(FILE *out)
{
    fprintf(out, "usage: anvil reference [CONFIG] [FILE...] -o FILE.pfm --spp N [--threads N]\n"
                 "                       [--seed S] [--albedo A] [--jitter] [--set PATH=VALUE]...\n"
                 "                       [--quiet]\n"
                 "Path-traces the config's view (Monte Carlo: all orders of scattering, sun and\n"
                 "sky) and writes the mean radiance to FILE.pfm and the standard error of each\n"
                 "pixel to FILE.stderr.pfm (docs/reference.md).\n"
                 "  --spp N      samples per pixel, at least 2 (for the standard error; default\n"
                 "               64)\n"
                 "  --threads N  worker threads (default: one per CPU); the image does not\n"
                 "               depend on it\n"
                 "  --seed S     random seed (default 1)\n"
                 "  --albedo A   single-scattering albedo in [0, 1] (default 1)\n"
                 "  --jitter     spread samples over each pixel (default: pixel centres, as the\n"
                 "               renderer samples)\n");
    return EXIT_USAGE;
}

static int parse_options(int argc, char **argv, struct reference_options *o)
{
    static const struct option longopts[] = {
        {"output", required_argument, NULL, 'o'},  {"spp", required_argument, NULL, 'n'},
        {"threads", required_argument, NULL, 't'}, {"seed", required_argument, NULL, 'r'},
        {"albedo", required_argument, NULL, 'a'},  {"jitter", no_argument, NULL, 'j'},
        {"set", required_argument, NULL, 's'},     {"quiet", no_argument, NULL, 'q'},
        {"help", no_argument, NULL, 'h'},          {NULL, 0, NULL, 0},
    };
    memset(o, 0, sizeof(*o));
    o->spp = 64;
    o->seed = 1;
    o->albedo = 1.0;
    optind = 1;
    int c;
    long v;
    while ((c = getopt_long(argc, argv, "o:qh", longopts, NULL)) != -1) {
        switch (c) {
        case 'o':
            o->output = optarg;
            break;
        case 'n':
            if (!app_option_long("reference", "--spp", optarg, 2, 1L << 30, &o->spp))
                return EXIT_BAD_INPUT;
            break;
        case 't':
            if (!app_option_long("reference", "--threads", optarg, 0, 4096, &o->threads))
                return EXIT_BAD_INPUT;
            break;
        case 'r':
            if (!app_option_long("reference", "--seed", optarg, 0, 0x7fffffffL, &v))
                return EXIT_BAD_INPUT;
            o->seed = (unsigned long long)v;
            break;
        case 'a':
            if (!app_option_double("reference", "--albedo", optarg, 0.0, 1.0, &o->albedo))
                return EXIT_BAD_INPUT;
            break;
        case 'j':
            o->jitter = true;
            break;
        case 's':
            if (o->n_sets == MAX_SETS) {
                log_error("too many --set options (at most %d)", MAX_SETS);
                return EXIT_USAGE;
            }
            o->sets[o->n_sets++] = optarg;
            break;
        case 'q':
            log_set_level(LOG_ERROR);
            break;
        case 'h':
            return -1;
        default:
            return EXIT_USAGE;
        }
    }
    o->args = argv + optind;
    o->n_args = argc - optind;
    if (!o->output) {
        log_error("reference: missing -o FILE.pfm");
        return EXIT_USAGE;
    }
    /* The names are checked before the paths are traced, which may take hours. */
    if (!image_path_supported(o->output)) {
        log_error("%s: unknown image type: expected a name ending in .pfm (or .png, tone-mapped)",
                  o->output);
        return EXIT_BAD_INPUT;
    }
    if (!frame_output_folder_exists(o->output))
        return EXIT_BAD_INPUT;
    return EXIT_OK;
}

/* FILE.pfm -> FILE.stderr.pfm (the extension, if any, replaced).  Caller frees. */
static char *stderr_path(const char *output)
{
    const char *slash = strrchr(output, '/');
    const char *dot = strrchr(output, '.');
    size_t stem = dot && (!slash || dot > slash) ? (size_t)(dot - output) : strlen(output);
    char *p = malloc(stem + sizeof(".stderr.pfm"));
    if (!p)
        return NULL;
    memcpy(p, output, stem);
    strcpy(p + stem, ".stderr.pfm");
    return p;
}

int cmd_reference(int argc, char **argv)
{
    struct reference_options o;
    int rc = parse_options(argc, argv, &o);
    if (rc < 0) {
        usage(stdout);
        return EXIT_OK;
    }
    if (rc == EXIT_USAGE)
        return usage(stderr);
    if (rc != EXIT_OK)
        return rc;

    struct config cfg;
    if (app_load_scene("reference", o.args, o.n_args, o.sets, o.n_sets, &cfg, &o.config) !=
        EXIT_OK)
        return EXIT_BAD_INPUT;
    double start = time_now_ms();
    struct ext_volume vol = {0};
    if (!scene_build_volume(&cfg, &vol))
        return EXIT_BAD_INPUT;
    rc = EXIT_FAILED;
    char *err_path = stderr_path(o.output);
    struct image mean = {0}, err = {0};
    struct traced_desc d = {
        .image = {.spp = (int)o.spp, .threads = (int)o.threads, .seed = o.seed, .jitter = o.jitter},
        .albedo = o.albedo,
    };
    double ms;
    if (!err_path || !traced_render(&cfg, &vol, &d, &mean, &err, &ms))
        goto done;
    if (!image_write(&mean, o.output, (float)cfg.render.exposure) ||
        !image_write_pfm(&err, err_path))
        goto done;
    log_info("wrote %s and %s (%dx%d, %ld spp, %.1f s; total %.1f s)", o.output, err_path,
             mean.width, mean.height, o.spp, ms / 1000.0, (time_now_ms() - start) / 1000.0);
    rc = EXIT_OK;
done:
    image_finish(&mean);
    image_finish(&err);
    free(err_path);
    ext_volume_finish(&vol);
    return rc;
}
