/*
 * common/fatal: how the program ends when a signal ends it.
 *
 * A library that crashes on a malformed file (netcdf-c and HDF5 do, on files we cannot check
 * in full) must not look like a crash of ours, and an interrupted write must not leave its
 * temporary file behind.  So:
 *
 *   - Code that hands a file to a library says so (fatal_enter ... fatal_leave).  A fatal
 *     signal there (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT) prints one line naming the
 *     library, the signal and the file, removes the temporary files, and exits with
 *     FATAL_EXIT_READING (a file the library could not read) or FATAL_EXIT_WRITING.
 *   - After main's work is done (fatal_exiting), a crash in a library's exit handler (HDF5's,
 *     after a failed write) says so and exits with the code the work had already.
 *   - A fatal signal anywhere else is a bug of ours: the temporary files are removed and the
 *     signal takes its course (a core dump, a sanitizer's report).
 *   - SIGINT, SIGTERM and SIGHUP remove the temporary files and exit with 128 + the signal
 *     (130, 143, 129): the write in progress is abandoned, the old file stays as it was.
 *     While a caller has asked for a graceful stop (fatal_stop_gracefully: a window's frame
 *     loop, which can end as if its window were closed), the first such signal is only
 *     recorded and said (fatal_stop_requested); a second one ends the program as above.
 *
 * Temporary files are those registered with fatal_track (file_write_atomic and the NetCDF
 * writers register theirs).  Everything the handler does is async-signal-safe: it writes
 * with write(2), removes with unlink(2), ends with _exit(2).
 *
 * Must not know: any other part.
 */
#ifndef ANVIL_COMMON_FATAL_H
#define ANVIL_COMMON_FATAL_H

#include <stdbool.h>

#define FATAL_EXIT_READING 1 /* as EXIT_BAD_INPUT: the file is what the library could not read */
#define FATAL_EXIT_WRITING 4 /* as EXIT_FAILED */

/* Installs the handlers (once; the program's main does it first thing). */
void fatal_install(void);

/* What the calling thread is doing inside a library: LIBRARY ("netCDF-C"), DOING
 * ("reading"), PATH.  The strings must stay valid until the matching fatal_leave.  SAVED
 * receives the scope this one replaces (scopes nest). */
struct fatal_scope {
    const char *library, *doing, *path;
    bool writing;
};
void fatal_enter(struct fatal_scope *saved, const char *library, const char *doing,
                 const char *path, bool writing);
void fatal_leave(const struct fatal_scope *saved);

/* Registers PATH (copied; at most 1023 bytes) as a temporary file to remove if a signal ends
 * the process.  False when all 32 slots are in use (the file is then simply not removed).
 * Thread safe. */
bool fatal_track(const char *path);
/* mkstemp(TEMPLATE) and fatal_track of the name it made, with SIGINT, SIGTERM and SIGHUP held
 * off between the two, so a signal cannot leave the file behind.  mkstemp's result (errno
 * set on -1). */
int fatal_mkstemp(char *template);
/* Forgets PATH (one not tracked is fine): once it is renamed into place or removed. */
void fatal_untrack(const char *path);

/* From ON on (true), the first SIGINT, SIGTERM or SIGHUP asks the caller to stop instead of
 * ending the program: fatal_stop_requested then returns it.  False restores the immediate
 * end (a signal recorded meanwhile stays recorded). */
void fatal_stop_gracefully(bool on);
/* The stop signal recorded while a graceful stop was on, or 0. */
int fatal_stop_requested(void);
/* "SIGTERM", ... ("a signal" for one this file does not handle). */
const char *fatal_signal_name(int sig);

/* The work is done and ends with exit code CODE: a crash from here on (a library's exit
 * handler) exits with CODE after saying so. */
void fatal_exiting(int code);

#endif
