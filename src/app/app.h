/*
 * app: the command line.  Each command parses its options, builds what it needs from the
 * parts below and returns one of the program's exit codes.
 *
 * Must not know: GL, file formats, the physics: it wires the parts below.
 */
#ifndef ANVIL_APP_H
#define ANVIL_APP_H

#include <stdbool.h>

#include "config/display_config.h"

/* Exit codes of the program (documented in docs/user-guide.md). */
enum {
    EXIT_OK = 0,
    EXIT_BAD_INPUT = 1, /* a config, data file or option value is wrong */
    EXIT_USAGE = 2,     /* the command line itself is wrong */
    EXIT_NO_GPU = 3,    /* no OpenGL 4.5 context could be made */
    EXIT_FAILED = 4,    /* the work failed for another reason (out of memory, write error) */
};
/* And from common/fatal.h: 128 + the signal after SIGHUP, SIGINT or SIGTERM (129, 130, 143);
 * 1 or 4 when a library crashed reading or writing a file. */

/* Number options, checked alike in every command (app/options.c): S, the value of OPTION of
 * COMMAND, as an integer (a number) in [LO, HI] into *OUT.  Otherwise false, with "COMMAND:
 * OPTION: expected an integer (a number) in [LO, HI], got "S"" logged. */
bool app_option_long(const char *command, const char *option, const char *s, long lo, long hi,
                     long *out);
bool app_option_double(const char *command, const char *option, const char *s, double lo,
                       double hi, double *out);

/* Sends each --set to the config it belongs to (app/options.c): those of the N_SETS in SETS
 * that name a display setting (display_config_has_setting) move to DISPLAY_SETS (room for
 * N_SETS), in order; the others stay in SETS, for the scene config.  Without a display file
 * (HAVE_DISPLAY false) a display setting is a mistake of the command line: logged ("X is a
 * display setting: it needs --display FILE"), false. */
bool app_route_sets(char **sets, int *n_sets, bool have_display, char **display_sets,
                    int *n_display_sets);

/* Loads the display config PATH, applies the display --set overrides SETS (app_route_sets)
 * and validates the result. */
bool app_load_display_config(const char *path, char *const *sets, int n_sets,
                             struct display_config *cfg);

int cmd_render(int argc, char **argv);
int cmd_run(int argc, char **argv);
int cmd_trackers(int argc, char **argv);
int cmd_probe(int argc, char **argv);

#endif
