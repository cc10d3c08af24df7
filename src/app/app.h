/*
 * app: the command line.  Each command parses its options, builds what it needs from the
 * parts below and returns one of the program's exit codes.
 */
#ifndef ANVIL_APP_H
#define ANVIL_APP_H

#include <stdbool.h>

/* Exit codes of the program (documented in docs/user-guide.md). */
enum {
    EXIT_OK = 0,
    EXIT_BAD_INPUT = 1, /* a config, data file or option value is wrong */
    EXIT_USAGE = 2,     /* the command line itself is wrong */
    EXIT_NO_GPU = 3,    /* no OpenGL 4.5 context could be made */
    EXIT_FAILED = 4,    /* the work failed for another reason (out of memory, write error) */
};

/* Number options, checked alike in every command (app/options.c): S, the value of OPTION of
 * COMMAND, as an integer (a number) in [LO, HI] into *OUT.  Otherwise false, with "COMMAND:
 * OPTION: expected an integer (a number) in [LO, HI], got "S"" logged. */
bool app_option_long(const char *command, const char *option, const char *s, long lo, long hi,
                     long *out);
bool app_option_double(const char *command, const char *option, const char *s, double lo,
                       double hi, double *out);

int cmd_render(int argc, char **argv);
int cmd_run(int argc, char **argv);

#endif
