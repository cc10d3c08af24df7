/*
 * app: the command line.  Each command parses its options, builds what it needs from the
 * parts below and returns one of the program's exit codes.
 *
 * Must not know: GL, file formats, the physics: it wires the parts below.
 */
#ifndef ANVIL_APP_H
#define ANVIL_APP_H

#include <stdbool.h>

#include "config/config.h"
#include "config/display_config.h"
#include "data/detect.h"

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

/* ---- the scene a command line names (app/scene_args.c, docs/data.md) ---------------------- */

#define APP_INPUTS_MAX_OWNED CONFIG_MAX_FILES

/* What the positional arguments of a command are: a config (only first), then data files,
 * folders and glob patterns of one kind, each known by its content (data_detect).  A pattern
 * that names no file itself is expanded here (glob(3), sorted): no match is an error naming
 * it; a WRF series keeps the pattern (the reader expands it alike, any number of files), an
 * extinction file or Isabel folder its one path. */
struct app_inputs {
    const char *config;                     /* the config, or NULL */
    const char *files[CONFIG_MAX_FILES];    /* paths and patterns, into the arguments or OWNED */
    int count;
    enum data_kind kind;                    /* of the files; DATA_KIND_UNREADABLE: none */
    char *owned[APP_INPUTS_MAX_OWNED];
    int n_owned;
};

/* Fills OUT from the N arguments ARGS of COMMAND.  False after one log_error (the file, what
 * it is, what was expected).  Free with app_inputs_finish. */
bool app_inputs_collect(const char *command, char **args, int n, struct app_inputs *out);
void app_inputs_finish(struct app_inputs *in);

/* The scene of the N arguments ARGS: the config (or the defaults) read, the files (if any)
 * as its data (scene.kind "data", data.format of their kind, data.files), the --set
 * overrides SETS applied, validated, and without a camera.* setting a camera that frames the
 * data (app_frame_camera).  *CONFIG_PATH (may be NULL) receives the config's path or NULL.
 * EXIT_OK, or EXIT_BAD_INPUT after one log_error. */
int app_load_scene(const char *command, char **args, int n, char **sets, int n_sets,
                   struct config *cfg, const char **config_path);

/* A scene of data without a camera.* setting gets the camera framing its domain
 * (scene_frame_camera, at render.width / render.height): written into CFG->camera, logged at
 * info level.  False (logged) when the data cannot be opened. */
bool app_frame_camera(struct config *cfg);

/* A tracked display (cave, hmd, openxr) without a navigation.* setting gets the navigation
 * fitting CFG's domain to its room (scene_frame_navigation), logged at info level.  FITTED
 * (may be NULL) receives that fit whether or not the display gives a navigation (what the
 * frame key brings back; DCFG's own navigation for other displays).  False (logged) when
 * the data cannot be opened. */
bool app_frame_navigation(const struct config *cfg, struct display_config *dcfg,
                          struct display_navigation *fitted);

int cmd_render(int argc, char **argv);
int cmd_run(int argc, char **argv);
int cmd_trackers(int argc, char **argv);
int cmd_probe(int argc, char **argv);

#endif
