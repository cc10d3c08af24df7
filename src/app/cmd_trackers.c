/* anvil trackers: a display's head and wand, live, in room coordinates (display/trackers.c). */
#include <getopt.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <time.h>

#include "app/app.h"
#include "common/log.h"
#include "display/display.h"

#define MAX_SETS 64

static volatile sig_atomic_t interrupted;

static void on_interrupt(int sig)
{
    (void)sig;
    interrupted = 1;
}

static int usage(FILE *out)
{
    fprintf(out,
            "usage: anvil trackers [--display] DISPLAY.cfg [--set PATH=VALUE]... [--seconds S] "
            "[--interval S] [--quiet]\n"
            "Prints the display's tracked head and wand (head.source, wand.source: dtrack or\n"
            "vrpn) as they arrive: position (m) and heading, pitch, roll (degrees) in room\n"
            "coordinates after calibration, tracked or not, poses per second, untracked\n"
            "frames, the wand's buttons and stick; per link frames, dropped frames and\n"
            "malformed input.  Walk to the walls' corners to check the calibration\n"
            "(docs/displays.md, \"Setting up a tracked CAVE\").  Until Ctrl-C, or S seconds.\n");
    return out == stdout ? EXIT_OK : EXIT_USAGE;
}

int cmd_trackers(int argc, char **argv)
{
    static const struct option longopts[] = {
        {"set", required_argument, NULL, 's'},
        {"seconds", required_argument, NULL, 'S'},
        {"interval", required_argument, NULL, 'i'},
        {"quiet", no_argument, NULL, 'q'},
        {"help", no_argument, NULL, 'h'},
        {"display", required_argument, NULL, 'D'},
        {NULL, 0, NULL, 0},
    };
    const char *display = NULL; /* --display FILE, as render and run take it */
    char *sets[MAX_SETS];
    int n_sets = 0;
    double seconds = INFINITY, interval = 0.5;
    optind = 1;
    int c;
    while ((c = getopt_long(argc, argv, "qh", longopts, NULL)) != -1) {
        switch (c) {
        case 'D':
            display = optarg;
            break;
        case 's':
            if (n_sets == MAX_SETS) {
                log_error("too many --set options (at most %d)", MAX_SETS);
                return EXIT_USAGE;
            }
            sets[n_sets++] = optarg;
            break;
        case 'S':
            if (!app_option_double("trackers", "--seconds", optarg, 0.0, 1e9, &seconds))
                return EXIT_BAD_INPUT;
            break;
        case 'i':
            if (!app_option_double("trackers", "--interval", optarg, 0.05, 3600.0, &interval))
                return EXIT_BAD_INPUT;
            break;
        case 'q':
            log_set_level(LOG_ERROR);
            break;
        case 'h':
            return usage(stdout);
        default:
            return usage(stderr);
        }
    }
    if (optind >= argc && !display) {
        log_error("trackers: missing DISPLAY.cfg");
        return usage(stderr);
    }
    const char *path = display ? display : argv[optind++];
    if (optind < argc) {
        log_error("trackers: unexpected argument \"%s\" (one display file)", argv[optind]);
        return usage(stderr);
    }
    char *display_sets[MAX_SETS];
    int n_display_sets;
    if (!app_route_sets(sets, &n_sets, true, display_sets, &n_display_sets))
        return EXIT_USAGE;
    if (n_sets > 0) {
        log_error("%s: not a display setting (trackers reads the display file only)", sets[0]);
        return EXIT_USAGE;
    }
    struct display_config cfg;
    if (!app_load_display_config(path, display_sets, n_display_sets, &cfg))
        return EXIT_BAD_INPUT;
    struct display_trackers *t = display_trackers_open(&cfg);
    if (!t)
        return EXIT_BAD_INPUT;
    signal(SIGINT, on_interrupt);
    signal(SIGTERM, on_interrupt);
    double start = time_now_ms();
    for (double next = interval;; next += interval) {
        double now = (time_now_ms() - start) * 1e-3;
        double wait = fmin(next, seconds) - now;
        if (wait > 0.0) {
            struct timespec ts = {.tv_sec = (time_t)wait,
                                  .tv_nsec = (long)((wait - floor(wait)) * 1e9)};
            nanosleep(&ts, NULL);
        }
        now = (time_now_ms() - start) * 1e-3;
        display_trackers_report(t, now, stdout);
        if (interrupted || now >= seconds - 1e-9)
            break;
    }
    display_trackers_close(t);
    return EXIT_OK;
}
