/*
 * common: the one logging function every part reports through, and small helpers that every
 * part needs (checked allocation, file reading).  Knows nothing about the renderer.
 *
 * Library code never prints or exits: it logs the reason for a failure here and returns
 * false or NULL.  The program decides what reaches stderr through the log level.
 *
 * Must not know: any other part (everything else may use it).
 */
#ifndef ANVIL_COMMON_LOG_H
#define ANVIL_COMMON_LOG_H

#include <stdbool.h>
#include <stddef.h>

enum log_level {
    LOG_NONE = -1, /* nothing printed (tests that provoke errors on purpose) */
    LOG_ERROR = 0,
    LOG_WARN = 1,
    LOG_INFO = 2,  /* progress and timing lines */
    LOG_DEBUG = 3, /* GL debug output, details */
};

/* Messages above this level are dropped.  Default LOG_INFO.  Thread safe. */
void log_set_level(enum log_level level);
enum log_level log_get_level(void);

/* The name each line starts with: "anvil" (a cluster's ranks: "anvil[2]"). */
void log_set_name(const char *name);

/* Formats one line to stderr, prefixed "anvil: " (and "error: "/"warning: ").  Thread safe. */
void log_msg(enum log_level level, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* A progress line at LOG_INFO.  On a terminal it is one line rewritten in place (other
 * messages print above it) until DONE ends it; elsewhere each call is a plain line (the caller
 * decides how often: common/progress.h).  Thread safe. */
void log_status(const char *line, bool done);
/* Whether stderr is a terminal that log_status rewrites in place. */
bool log_status_is_terminal(void);

/* Counts of errors and warnings logged so far (tests use them). */
unsigned log_error_count(void);
unsigned log_warn_count(void);

/* Keeps the last error message logged, for tests to check wording.  Valid until the next
 * log_msg call from any thread. */
const char *log_last_error(void);
/* The same for the last warning. */
const char *log_last_warning(void);

#define log_error(...) log_msg(LOG_ERROR, __VA_ARGS__)
#define log_warn(...) log_msg(LOG_WARN, __VA_ARGS__)
#define log_info(...) log_msg(LOG_INFO, __VA_ARGS__)
#define log_debug(...) log_msg(LOG_DEBUG, __VA_ARGS__)

/* The largest text file the program reads whole (configs and their @includes, scripts, head
 * paths, transfer functions, shaders, fonts): 64 MiB. */
#define FILE_TEXT_MAX ((size_t)64 << 20)

/* Opens PATH for reading when it is a regular file, without waiting on a FIFO: anything else
 * (a FIFO, a device such as /dev/zero, a folder) is refused.  Returns the descriptor, or -1
 * with the reason in WHY ("not a regular file (a FIFO)", strerror's words); logs nothing. */
int file_open_regular(const char *path, char *why, size_t why_size);

/* Reads the regular file PATH (file_open_regular) whole into a NUL-terminated buffer the
 * caller frees, refusing a file of more than MAX bytes before reading it (and one that grows
 * past MAX while read).  On failure returns NULL with the reason in WHY; logs nothing.
 * *LEN_OUT (may be NULL) receives the length. */
char *file_read_text(const char *path, size_t max, size_t *len_out, char *why, size_t why_size);

/* file_read_text with MAX = FILE_TEXT_MAX that logs "PATH: reason" on failure. */
char *file_read_all(const char *path, size_t *len_out);

/* Where a file written to PATH goes (every writer asks first): PATH itself, or, when PATH is
 * a symbolic link, the file it points to (so the link stays a link).  An existing target must
 * be a regular file that may be written: a read-only one (no write permission for us, or for
 * anyone) is refused rather than replaced.  TARGET (SIZE bytes) receives the path to write and
 * *MODE the permissions to give it (the existing file's, else 0666 less the umask).  False
 * after one log_error naming PATH. */
bool file_write_target(const char *path, char *target, size_t size, unsigned *mode);

/* Writes LEN bytes to PATH atomically (file_write_target, then a temporary file in the same
 * folder, fsync, rename).  On failure the old file is untouched and the reason is logged. */
bool file_write_atomic(const char *path, const void *data, size_t len);

/* Monotonic time in milliseconds. */
double time_now_ms(void);

#endif
