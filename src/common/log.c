#include "common/log.h"

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/fatal.h"

static pthread_mutex_t log_lock = PTHREAD_MUTEX_INITIALIZER;
static enum log_level current_level = LOG_INFO;
static unsigned errors, warnings;
static char last_error[1024];
static char last_warning[1024];
static char who[32] = "anvil"; /* the program's name in each line (log_set_name) */
static char status[256]; /* the status line on a terminal (log_status), or "" */
static int status_tty = -1; /* whether stderr is a terminal: -1 not asked yet */

void log_set_level(enum log_level level)
{
    pthread_mutex_lock(&log_lock);
    current_level = level;
    pthread_mutex_unlock(&log_lock);
}

enum log_level log_get_level(void)
{
    return current_level;
}

void log_set_name(const char *name)
{
    pthread_mutex_lock(&log_lock);
    snprintf(who, sizeof(who), "%s", name);
    pthread_mutex_unlock(&log_lock);
}

void log_msg(enum log_level level, const char *fmt, ...)
{
    char line[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof(line), fmt, ap);
    va_end(ap);

    pthread_mutex_lock(&log_lock);
    if (level == LOG_ERROR) {
        errors++;
        snprintf(last_error, sizeof(last_error), "%s", line);
    } else if (level == LOG_WARN) {
        warnings++;
        snprintf(last_warning, sizeof(last_warning), "%s", line);
    }
    if ((int)level <= (int)current_level) {
        const char *tag = level == LOG_ERROR ? "error: " : level == LOG_WARN ? "warning: " : "";
        if (status[0]) /* the message goes above the status line, which stays at the bottom */
            fprintf(stderr, "\r\033[K");
        fprintf(stderr, "%s: %s%s\n", who, tag, line);
        if (status[0])
            fprintf(stderr, "%s: %s", who, status);
    }
    pthread_mutex_unlock(&log_lock);
}

bool log_status_is_terminal(void)
{
    pthread_mutex_lock(&log_lock);
    if (status_tty < 0)
        status_tty = isatty(fileno(stderr)) && getenv("TERM") && strcmp(getenv("TERM"), "dumb");
    bool tty = status_tty;
    pthread_mutex_unlock(&log_lock);
    return tty;
}

void log_status(const char *line, bool done)
{
    bool tty = log_status_is_terminal();
    pthread_mutex_lock(&log_lock);
    if ((int)LOG_INFO <= (int)current_level) {
        if (!tty) {
            fprintf(stderr, "%s: %s\n", who, line);
        } else {
            fprintf(stderr, "\r\033[K%s: %s%s", who, line, done ? "\n" : "");
            fflush(stderr);
        }
    }
    if (tty && !done)
        snprintf(status, sizeof(status), "%s", line);
    else
        status[0] = '\0';
    pthread_mutex_unlock(&log_lock);
}

unsigned log_error_count(void)
{
    return errors;
}

unsigned log_warn_count(void)
{
    return warnings;
}

const char *log_last_error(void)
{
    return last_error;
}

const char *log_last_warning(void)
{
    return last_warning;
}

int file_open_regular(const char *path, char *why, size_t why_size)
{
    /* O_NONBLOCK: opening a FIFO for reading would wait for a writer. */
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        snprintf(why, why_size, "cannot open: %s", strerror(errno));
        return -1;
    }
    struct stat st;
    if (fstat(fd, &st) != 0) {
        snprintf(why, why_size, "cannot read: %s", strerror(errno));
        close(fd);
        return -1;
    }
    if (!S_ISREG(st.st_mode)) {
        const char *kind = S_ISDIR(st.st_mode)    ? "a folder"
                           : S_ISFIFO(st.st_mode) ? "a FIFO"
                           : S_ISCHR(st.st_mode)  ? "a character device"
                           : S_ISBLK(st.st_mode)  ? "a block device"
                           : S_ISSOCK(st.st_mode) ? "a socket"
                                                  : "not a file";
        snprintf(why, why_size, "not a regular file (%s)", kind);
        close(fd);
        return -1;
    }
    int flags = fcntl(fd, F_GETFL);
    if (flags >= 0)
        fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
    return fd;
}

/* "64 MiB", "512 KiB", "100 bytes". */
static void format_size(size_t n, char *buf, size_t size)
{
    if (n >= ((size_t)1 << 20) && n % ((size_t)1 << 20) == 0)
        snprintf(buf, size, "%zu MiB", n >> 20);
    else if (n >= 1024 && n % 1024 == 0)
        snprintf(buf, size, "%zu KiB", n >> 10);
    else
        snprintf(buf, size, "%zu bytes", n);
}

char *file_read_text(const char *path, size_t max, size_t *len_out, char *why, size_t why_size)
{
    int fd = file_open_regular(path, why, why_size);
    if (fd < 0)
        return NULL;
    char limit[32];
    format_size(max, limit, sizeof(limit));
    struct stat st;
    if (fstat(fd, &st) == 0 && (uint64_t)st.st_size > (uint64_t)max) {
        snprintf(why, why_size, "%lld bytes: larger than the %s a file of this kind may be",
                 (long long)st.st_size, limit);
        close(fd);
        return NULL;
    }
    /* The size is a hint (a file may grow while read, /proc files say 0): read to the end. */
    size_t cap = st.st_size > 0 ? (size_t)st.st_size + 1 : 4096, len = 0;
    char *buf = malloc(cap);
    if (!buf)
        goto error_memory;
    for (;;) {
        if (len + 1 >= cap) {
            if (cap >= max + 2) { /* more than MAX bytes read */
                snprintf(why, why_size, "larger than the %s a file of this kind may be", limit);
                goto error_buf;
            }
            size_t grown_cap = cap * 2 > max + 2 ? max + 2 : cap * 2;
            char *grown = realloc(buf, grown_cap);
            if (!grown)
                goto error_memory;
            buf = grown;
            cap = grown_cap;
        }
        ssize_t n = read(fd, buf + len, cap - len - 1);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            snprintf(why, why_size, "read failed: %s", strerror(errno));
            goto error_buf;
        }
        if (n == 0)
            break;
        len += (size_t)n;
    }
    if (len > max) {
        snprintf(why, why_size, "larger than the %s a file of this kind may be", limit);
        goto error_buf;
    }
    close(fd);
    buf[len] = '\0';
    if (len_out)
        *len_out = len;
    return buf;

error_memory:
    snprintf(why, why_size, "out of memory reading it");
error_buf:
    free(buf);
    close(fd);
    return NULL;
}

char *file_read_all(const char *path, size_t *len_out)
{
    char why[160];
    char *text = file_read_text(path, FILE_TEXT_MAX, len_out, why, sizeof(why));
    if (!text)
        log_error("%s: %s", path, why);
    return text;
}

bool file_write_target(const char *path, char *target, size_t size, unsigned *mode)
{
    mode_t mask = umask(0);
    umask(mask);
    *mode = 0666 & ~mask;
    struct stat st;
    if (lstat(path, &st) != 0) {
        if (errno != ENOENT) {
            log_error("%s: cannot write: %s", path, strerror(errno));
            return false;
        }
        if (snprintf(target, size, "%s", path) >= (int)size) {
            log_error("%s: path too long", path);
            return false;
        }
        return true; /* a new file */
    }
    if (S_ISLNK(st.st_mode)) {
        /* Through the link: the file it points to is replaced, the link stays. */
        char *real = realpath(path, NULL);
        if (!real) {
            log_error("%s: a symbolic link to %s: %s", path,
                      errno == ENOENT ? "a file that does not exist" : "a file not reached",
                      strerror(errno));
            return false;
        }
        bool fits = snprintf(target, size, "%s", real) < (int)size;
        free(real);
        if (!fits || stat(target, &st) != 0) {
            log_error("%s: the file its link points to cannot be written", path);
            return false;
        }
    } else if (snprintf(target, size, "%s", path) >= (int)size) {
        log_error("%s: path too long", path);
        return false;
    }
    if (!S_ISREG(st.st_mode)) {
        log_error("%s: not a regular file: not replaced", path);
        return false;
    }
    bool read_only = (st.st_mode & (S_IWUSR | S_IWGRP | S_IWOTH)) == 0;
    if (read_only || access(target, W_OK) != 0) {
        log_error("%s: %s (mode %04o): not replaced (make it writable, or save under another "
                  "name)",
                  path, read_only ? "read-only" : "not writable by this user",
                  (unsigned)(st.st_mode & 07777));
        return false;
    }
    *mode = st.st_mode & 07777;
    return true;
}

bool file_write_atomic(const char *path, const void *data, size_t len)
{
    char target[4096];
    unsigned mode;
    if (!file_write_target(path, target, sizeof(target), &mode))
        return false;
    size_t plen = strlen(target);
    char *tmp = malloc(plen + 16);
    if (!tmp) {
        log_error("%s: out of memory", path);
        return false;
    }
    snprintf(tmp, plen + 16, "%s.tmpXXXXXX", target);
    int fd = fatal_mkstemp(tmp); /* removed if a signal ends the process before the rename */
    if (fd < 0) {
        log_error("%s: cannot create a temporary file beside it: %s", path, strerror(errno));
        free(tmp);
        return false;
    }
    /* mkstemp makes the file 0600: give it the old file's mode, or what a plain create would. */
    if (fchmod(fd, (mode_t)mode) != 0)
        log_warn("%s: cannot set the file's permissions: %s", path, strerror(errno));
    const char *p = data;
    size_t left = len;
    while (left > 0) {
        ssize_t n = write(fd, p, left);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            log_error("%s: write failed: %s", path, strerror(errno));
            goto error_tmp;
        }
        p += n;
        left -= (size_t)n;
    }
    if (fsync(fd) != 0) {
        log_error("%s: fsync failed: %s", path, strerror(errno));
        goto error_tmp;
    }
    if (close(fd) != 0) {
        fd = -1;
        log_error("%s: close failed: %s", path, strerror(errno));
        goto error_tmp;
    }
    fd = -1;
    if (rename(tmp, target) != 0) {
        log_error("%s: cannot replace: %s", path, strerror(errno));
        goto error_tmp;
    }
    fatal_untrack(tmp);
    free(tmp);
    return true;

error_tmp:
    if (fd >= 0)
        close(fd);
    unlink(tmp);
    fatal_untrack(tmp);
    free(tmp);
    return false;
}

double time_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}
