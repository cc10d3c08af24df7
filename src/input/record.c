/*
 * Recordings: every frame of a run in the script format (docs/menu.md), written as it goes to
 * a temporary file beside the recording and renamed into place at the end.  Floats are
 * written with 9 significant digits and doubles with 17, which read back to the same bits,
 * so a replay feeds the session exactly what the run saw.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/fatal.h"
#include "common/log.h"
#include "input/input.h"

struct input_recorder {
    FILE *file;
    char path[1024], target[4096], temp[4200];
    bool failed;
    long frames;
};

struct input_recorder *input_recorder_open(const char *path, const char *command, bool menu_shown)
{
    struct input_recorder *r = calloc(1, sizeof(*r));
    if (!r) {
        log_error("%s: out of memory", path);
        return NULL;
    }
    if (strlen(path) >= sizeof(r->path)) {
        log_error("%s: path too long", path);
        free(r);
        return NULL;
    }
    snprintf(r->path, sizeof(r->path), "%s", path);
    /* Written beside its target (through a link; never over a read-only file) and renamed
     * into place at the end; a signal removes it (common/fatal). */
    unsigned mode = 0644;
    if (!file_write_target(path, r->target, sizeof(r->target), &mode)) {
        free(r);
        return NULL;
    }
    snprintf(r->temp, sizeof(r->temp), "%s.tmpXXXXXX", r->target);
    int fd = fatal_mkstemp(r->temp);
    if (fd >= 0 && fchmod(fd, (mode_t)mode) != 0)
        log_warn("%s: cannot set the file's permissions: %s", path, strerror(errno));
    r->file = fd >= 0 ? fdopen(fd, "w") : NULL;
    if (!r->file) {
        log_error("%s: cannot write: %s", fd >= 0 ? r->temp : path, strerror(errno));
        if (fd >= 0) {
            close(fd);
            remove(r->temp);
            fatal_untrack(r->temp);
        }
        free(r);
        return NULL;
    }
    fprintf(r->file,
            "# anvil recording (docs/menu.md, \"Recordings\"): replay with --input\n"
            "recorded %s\nmenu %s\n",
            command, menu_shown ? "shown" : "hidden");
    return r;
}

static void event_line(FILE *f, long frame, const struct input_event *e)
{
    switch (e->type) {
    case INPUT_BUTTON:
        fprintf(f, "%ld button %s %s\n", frame, input_button_name(e->button),
                e->down ? "down" : "up");
        return;
    case INPUT_POSE:
        fprintf(f, "%ld pose %s %.9g %.9g %.9g %.9g %.9g %.9g", frame,
                e->space == INPUT_SPACE_WORLD ? "world" : "tracker", e->position[0], e->position[1],
                e->position[2], e->direction[0], e->direction[1], e->direction[2]);
        if (e->has_up)
            fprintf(f, " %.9g %.9g %.9g", e->up[0], e->up[1], e->up[2]);
        fprintf(f, "\n");
        return;
    case INPUT_AXIS:
        if (e->axis >= 0 && e->axis < INPUT_AXIS_COUNT)
            fprintf(f, "%ld axis %s %.9g\n", frame, e->axis == INPUT_AXIS_FLY ? "fly" : "turn",
                    e->value);
        return;
    case INPUT_KEY:
        if (e->key != INPUT_KEY_NONE)
            fprintf(f, "%ld key %s\n", frame, input_key_name(e->key));
        return;
    case INPUT_AIM:
        fprintf(f, "%ld aim %s %.9g %.9g\n", frame, e->target, e->u, e->v);
        return;
    case INPUT_DRAG:
        fprintf(f, "%ld drag %.9g %.9g\n", frame, e->u, e->v);
        return;
    case INPUT_SCROLL:
        fprintf(f, "%ld scroll %.9g\n", frame, e->value);
        return;
    }
}

void input_recorder_frame(struct input_recorder *r, const struct input_record_frame *f,
                          const struct input_queue *events)
{
    if (!r || r->failed)
        return;
    FILE *out = r->file;
    fprintf(out, "%ld time %.17g %.17g\n", f->frame, f->time_s, f->dt_s);
    for (int i = 0; events && i < events->count; i++)
        event_line(out, f->frame, &events->events[i]);
    if (f->have_head)
        fprintf(out, "%ld head %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", f->frame, f->head_position[0],
                f->head_position[1], f->head_position[2], f->head_rotation[0], f->head_rotation[1],
                f->head_rotation[2], f->head_rotation[3]);
    if (f->have_head && f->have_eyes) {
        fprintf(out, "%ld eyes", f->frame);
        for (int e = 0; e < 2; e++)
            fprintf(out, " %.9g %.9g %.9g %.9g %.9g %.9g %.9g", f->eye_position[e][0],
                    f->eye_position[e][1], f->eye_position[e][2], f->eye_rotation[e][0],
                    f->eye_rotation[e][1], f->eye_rotation[e][2], f->eye_rotation[e][3]);
        fputc('\n', out);
    }
    fprintf(out, "%ld cursor %d %.17g %d\n", f->frame, f->step, f->step_acc, f->playing);
    r->frames++;
    if (ferror(out)) {
        log_error("%s: cannot write: %s", r->temp, strerror(errno));
        r->failed = true;
    }
}

bool input_recorder_close(struct input_recorder *r)
{
    if (!r)
        return true;
    bool ok = !r->failed && fflush(r->file) == 0 && fsync(fileno(r->file)) == 0;
    if (!ok && !r->failed)
        log_error("%s: cannot write: %s", r->temp, strerror(errno));
    ok = fclose(r->file) == 0 && ok;
    if (ok && rename(r->temp, r->target) != 0) {
        log_error("%s: cannot rename into place: %s", r->path, strerror(errno));
        ok = false;
    }
    if (ok)
        log_info("recorded %ld frames to %s", r->frames, r->path);
    else
        remove(r->temp);
    fatal_untrack(r->temp);
    free(r);
    return ok;
}
