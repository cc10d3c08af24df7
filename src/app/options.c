/* Number options of the commands (app.h). */
#include <errno.h>
#include <stdlib.h>

#include "app/app.h"
#include "common/log.h"

bool app_option_long(const char *command, const char *option, const char *s, long lo, long hi,
                     long *out)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno || end == s || *end || v < lo || v > hi) {
        log_error("%s: %s: expected an integer in [%ld, %ld], got \"%s\"", command, option, lo, hi,
                  s);
        return false;
    }
    *out = v;
    return true;
}

bool app_option_double(const char *command, const char *option, const char *s, double lo, double hi,
                       double *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (errno || end == s || *end || !(v >= lo && v <= hi)) {
        log_error("%s: %s: expected a number in [%g, %g], got \"%s\"", command, option, lo, hi, s);
        return false;
    }
    *out = v;
    return true;
}
