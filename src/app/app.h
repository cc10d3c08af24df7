/*
 * app: the command line.  Each command parses its options, builds what it needs from the
 * parts below and returns one of the program's exit codes.
 */
#ifndef ANVIL_APP_H
#define ANVIL_APP_H

/* Exit codes of the program (documented in docs/user-guide.md). */
enum {
    EXIT_OK = 0,
    EXIT_BAD_INPUT = 1, /* a config, data file or option value is wrong */
    EXIT_USAGE = 2,     /* the command line itself is wrong */
    EXIT_NO_GPU = 3,    /* no OpenGL 4.5 context could be made */
    EXIT_FAILED = 4,    /* the work failed for another reason (out of memory, write error) */
};

int cmd_render(int argc, char **argv);
int cmd_run(int argc, char **argv);

#endif
