/*
 * config/config_table: the settings engine that scene files (config.c) and display files
 * (display_config.c) share.  Private to src/config/: nothing outside this part includes it.
 *
 * A table lists every setting one kind of file may hold: its path, type, range, default,
 * where in the struct it is stored, and a line of help.  From the table alone the engine
 * fills a struct with the defaults, reads a file into it (@include resolved relative to the
 * including file; every message "FILE:LINE: SETTING: expected ..."), applies "--set
 * PATH=VALUE" with the same checks, and writes the markdown reference.  What the engine
 * cannot know (settings that depend on each other, derived values) stays with the caller.
 */
#ifndef ANVIL_CONFIG_TABLE_H
#define ANVIL_CONFIG_TABLE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

enum config_type {
    T_BOOL,
    T_INT,
    T_UINT,
    T_DOUBLE,
    T_ENUM,   /* one of NAMES, stored as its index in an int */
    T_STRING, /* 1 to SIZE - 1 characters in a char[SIZE] (device and wall names) */
    T_PATH,   /* a file name in a char[SIZE], resolved against the folder of the file that
                 names it; from --set kept as given (relative to the working folder) */
    T_FILES,  /* data.files: up to MAX paths resolved as T_PATH (glob patterns kept), in a
                 char[CONFIG_MAX_FILES][CONFIG_PATH_MAX] at OFFSET, their count in an int at
                 COUNT_OFFSET */
    T_GROUPS, /* a list ( { ... }, ... ) of MIN to MAX groups, each filled through the table
                 ELEMS into an array at OFFSET, their count in an int at COUNT_OFFSET */
    T_TRANSFER, /* a transfer function (struct transfer_function at OFFSET): the name of a
                   transfer function file (config/transfer_file.h), resolved as T_PATH, or its
                   group written in place; from --set a file name */
};

enum {
    F_MIN_OPEN = 1 << 0,
    F_MAX_OPEN = 1 << 1,
    F_SPECIES = 1 << 2,        /* one setting per species; '*' in the path is species_name() */
    F_OPTICS_DEFAULT = 1 << 3, /* the default is not in the table: the caller fills it */
    F_REQUIRED = 1 << 4,       /* in an element table: every element of the list must set it */
    F_GIVEN = 1 << 5,          /* the bool at GIVEN is set true when a file or --set gives it */
    F_UP_TO = 1 << 6,          /* T_DOUBLE with N > 1: an array of 0 to N numbers, how many
                                  in the int at COUNT_OFFSET */
};

struct config_table;

struct config_field {
    const char *path;
    enum config_type type;
    int n;           /* numbers in a vector; 1 for a scalar */
    size_t offset;   /* into the struct (of species 0 with F_SPECIES) */
    size_t stride;   /* F_SPECIES: bytes from one species to the next */
    double min, max; /* of each number; T_GROUPS: of the element count; T_FILES: max count */
    unsigned flags;
    double scale;                     /* stored = written * scale; 0 means 1 */
    const char *const *names;         /* T_ENUM: NULL-terminated, in enum order */
    double def[6];                    /* numbers, bools as 0/1, enums as their index */
    const char *def_text;             /* T_STRING, T_PATH: the default (NULL: "") */
    size_t size;                      /* T_STRING, T_PATH: bytes of the buffer */
    size_t given;                     /* F_GIVEN: offset of the bool */
    size_t count_offset;              /* T_FILES, T_GROUPS, F_UP_TO: offset of the int count */
    const struct config_table *elems; /* T_GROUPS: the table of one element */
    const void *def_elems;            /* T_GROUPS: the default elements ... */
    int def_count;                    /* ... and how many */
    const char *shown_default;        /* the reference's default column when the stored default is
                                         not what applies ("display.mode", "the device's") */
    const char *help;
};

struct config_table {
    const struct config_field *fields;
    int count;
    size_t size;           /* of the struct the table fills (of one element for ELEMS) */
    const char *example;   /* an assignment for "expected SETTING=VALUE, e.g. ..." */
    const char *elem_name; /* an element table: what one element is ("wall") */
    /* The wording of messages (the two kinds of files have always differed; their tests pin
     * both):
     *   list_known:    an unknown name is answered with the known ones, "expected a known
     *                  setting (did you mean head.position?)", "expected a known group
     *                  (display, head, ...)"; else "unknown setting (did you mean ...?)".
     *   whole_vectors: a vector is judged as a whole, "PATH: expected [3 numbers] each a
     *                  number in [a, b], got [...]"; else element by element, "PATH[1]:
     *                  expected a number in [a, b], got 0". */
    bool list_known;
    bool whole_vectors;
};

/* Where a file put each setting and group (a list element is "walls.[2]"), for messages of
 * the caller's own checks after the file is read.  Zero-initialise; config_trace_finish
 * frees it. */
struct config_trace_entry {
    char *path;
    char *file;
    int line;
};

struct config_trace {
    struct config_trace_entry *entries;
    int count, cap;
};

/* Zeroes the struct at BASE (T->size bytes) and stores every default of T, but not those
 * with F_OPTICS_DEFAULT. */
void config_table_defaults(const struct config_table *t, void *base);

/* Reads the file PATH (with its @includes) into BASE on top of what is there.  On failure
 * logs one message "FILE:LINE: SETTING: expected ..." and returns false; BASE then holds
 * whatever was read before.  TRACE (may be NULL) records where each setting was read. */
bool config_table_read(const struct config_table *t, const char *path, void *base,
                       struct config_trace *trace);

/* Applies one "PATH=VALUE" (the --set option) to BASE.  A list element's setting is
 * "walls.[2].mode", for an element that exists.  On failure logs "--set PATH: expected ..."
 * and returns false with BASE untouched. */
bool config_table_set(const struct config_table *t, void *base, const char *assignment);

/* True when PATH ("PATH" or "PATH=VALUE") lies in one of T's top-level groups or names one
 * of its top-level settings, known below that level or not ("head.postion" is the display
 * table's: its messages then suggest head.position). */
bool config_table_owns(const struct config_table *t, const char *path);

/* Writes T as a markdown table: setting, type, default (read from DEFAULTS, a struct filled
 * with T's defaults), range, description.  A list's element settings follow it as
 * "walls.[i].name". */
void config_table_write_reference(const struct config_table *t, const void *defaults, FILE *out);

/* The file and line (0: unknown) where the last read put PATH.  False when it did not. */
bool config_trace_find(const struct config_trace *trace, const char *path, const char **file,
                       int *line);
void config_trace_finish(struct config_trace *trace);

#endif
