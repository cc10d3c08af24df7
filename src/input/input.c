/* The event queue, names, the source table's dispatch and the scripted source. */
#include "input/input.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "input/input_impl.h"

static const char *const button_names[INPUT_BUTTON_COUNT] = {"trigger", "grab", "menu", "reset"};
static const char *const axis_names[INPUT_AXIS_COUNT] = {"fly", "turn"};
static const struct {
    const char *name;
    enum input_key key;
} key_names[] = {
    {"play", INPUT_KEY_PLAY},
    {"back", INPUT_KEY_STEP_BACK},
    {"forward", INPUT_KEY_STEP_FORWARD},
    {"menu", INPUT_KEY_MENU},
    {"next-page", INPUT_KEY_PAGE_NEXT},
    {"prev-page", INPUT_KEY_PAGE_PREV},
    {"quit", INPUT_KEY_QUIT},
    {"move-forward", INPUT_KEY_MOVE_FORWARD},
    {"move-back", INPUT_KEY_MOVE_BACK},
    {"move-left", INPUT_KEY_MOVE_LEFT},
    {"move-right", INPUT_KEY_MOVE_RIGHT},
    {"move-up", INPUT_KEY_MOVE_UP},
    {"move-down", INPUT_KEY_MOVE_DOWN},
    {"turn-left", INPUT_KEY_TURN_LEFT},
    {"turn-right", INPUT_KEY_TURN_RIGHT},
    {"turn-up", INPUT_KEY_TURN_UP},
    {"turn-down", INPUT_KEY_TURN_DOWN},
    {"zoom-in", INPUT_KEY_ZOOM_IN},
    {"zoom-out", INPUT_KEY_ZOOM_OUT},
    {"sun-left", INPUT_KEY_SUN_LEFT},
    {"sun-right", INPUT_KEY_SUN_RIGHT},
    {"sun-up", INPUT_KEY_SUN_UP},
    {"sun-down", INPUT_KEY_SUN_DOWN},
    {"screenshot", INPUT_KEY_SCREENSHOT},
    {"bookmark", INPUT_KEY_BOOKMARK},
    {"path-key", INPUT_KEY_PATH_KEY},
    {"path-play", INPUT_KEY_PATH_PLAY},
    {"probe", INPUT_KEY_PROBE},
    {"frame", INPUT_KEY_FRAME},
};

void input_queue_clear(struct input_queue *q)
{
    q->count = 0;
    q->dropped = 0;
}

void input_queue_push(struct input_queue *q, const struct input_event *e)
{
    if (q->count >= INPUT_QUEUE_MAX) {
        q->dropped++;
        return;
    }
    q->events[q->count++] = *e;
}

const char *input_button_name(enum input_button b)
{
    return b >= 0 && b < INPUT_BUTTON_COUNT ? button_names[b] : "?";
}

bool input_button_from_name(const char *name, enum input_button *out)
{
    for (int i = 0; i < INPUT_BUTTON_COUNT; i++) {
        if (strcmp(name, button_names[i]) == 0) {
            *out = (enum input_button)i;
            return true;
        }
    }
    return false;
}

bool input_axis_from_name(const char *name, enum input_axis *out)
{
    for (int i = 0; i < INPUT_AXIS_COUNT; i++) {
        if (strcmp(name, axis_names[i]) == 0) {
            *out = (enum input_axis)i;
            return true;
        }
    }
    return false;
}

const char *input_key_name(enum input_key k)
{
    for (size_t i = 0; i < sizeof(key_names) / sizeof(key_names[0]); i++)
        if (key_names[i].key == k)
            return key_names[i].name;
    return "?";
}

bool input_key_from_name(const char *name, enum input_key *out)
{
    for (size_t i = 0; i < sizeof(key_names) / sizeof(key_names[0]); i++) {
        if (strcmp(name, key_names[i].name) == 0) {
            *out = key_names[i].key;
            return true;
        }
    }
    return false;
}

bool input_source_poll(struct input_source *s, const struct input_frame *frame,
                       struct input_queue *q)
{
    return s->impl->poll(s, frame, q);
}

bool input_source_finished(const struct input_source *s)
{
    return s->impl->finished && s->impl->finished(s);
}

const char *input_source_name(const struct input_source *s)
{
    return s->impl->name;
}

void input_source_destroy(struct input_source *s)
{
    if (s)
        s->impl->destroy(s);
}

/* ---- scripted input ------------------------------------------------------------------- */

struct timed_event {
    long frame;
    int line; /* in the script, for messages */
    struct input_event event;
};

struct frame_info {
    long frame;
    struct input_script_frame info;
};

struct script {
    struct input_source base;
    struct timed_event *events;
    int count, next;
    double fps;
    struct frame_info *frames; /* a recording's per-frame lines, ascending */
    int frame_count, frame_cap;
    bool recorded, from_run, has_head;
    int menu_shown;
    long polled; /* the last frame polled */
    char *path;
};

static bool script_poll(struct input_source *s, const struct input_frame *frame,
                        struct input_queue *q)
{
    struct script *sc = (struct script *)s;
    while (sc->next < sc->count && sc->events[sc->next].frame <= frame->frame)
        input_queue_push(q, &sc->events[sc->next++].event);
    sc->polled = frame->frame;
    return true;
}

/* Every event delivered, and every frame a recording describes polled. */
static bool script_finished(const struct input_source *s)
{
    const struct script *sc = (const struct script *)s;
    return sc->next >= sc->count &&
           (sc->frame_count == 0 || sc->polled >= sc->frames[sc->frame_count - 1].frame);
}

static void script_destroy(struct input_source *s)
{
    struct script *sc = (struct script *)s;
    free(sc->events);
    free(sc->frames);
    free(sc->path);
    free(sc);
}

static const struct input_source_impl script_impl = {
    .name = "script",
    .poll = script_poll,
    .finished = script_finished,
    .destroy = script_destroy,
};

static bool parse_float(const char *tok, float *out)
{
    if (!tok)
        return false;
    char *end;
    errno = 0;
    double v = strtod(tok, &end);
    if (*end || end == tok || errno || !isfinite(v))
        return false;
    *out = (float)v;
    return true;
}

/* Parses the words after the frame number into E.  Returns NULL, or what was expected. */
static const char *parse_event(char **tok, int n, struct input_event *e)
{
    memset(e, 0, sizeof(*e));
    const char *kind = tok[0];
    if (strcmp(kind, "button") == 0) {
        e->type = INPUT_BUTTON;
        if (n != 3 || !input_button_from_name(tok[1], &e->button))
            return "\"button trigger|grab|menu|reset down|up\"";
        if (strcmp(tok[2], "down") != 0 && strcmp(tok[2], "up") != 0)
            return "\"button NAME down\" or \"button NAME up\"";
        e->down = strcmp(tok[2], "down") == 0;
        return NULL;
    }
    if (strcmp(kind, "key") == 0) {
        e->type = INPUT_KEY;
        if (n != 2 || !input_key_from_name(tok[1], &e->key))
            return "\"key NAME\" with a key of docs/menu.md (play, back, forward, menu, "
                   "next-page, prev-page, quit, move-forward, ..., sun-down)";
        return NULL;
    }
    if (strcmp(kind, "axis") == 0) {
        e->type = INPUT_AXIS;
        if (n != 3 || !input_axis_from_name(tok[1], &e->axis) || !parse_float(tok[2], &e->value) ||
            e->value < -1.0f || e->value > 1.0f)
            return "\"axis fly|turn VALUE\" with VALUE in [-1, 1]";
        return NULL;
    }
    if (strcmp(kind, "aim") == 0) {
        e->type = INPUT_AIM;
        e->u = e->v = 0.5f;
        if ((n != 2 && n != 4) || strlen(tok[1]) >= INPUT_TARGET_MAX ||
            (n == 4 && (!parse_float(tok[2], &e->u) || !parse_float(tok[3], &e->v))))
            return "\"aim WIDGET [U V]\" (U, V in [0, 1] on the widget)";
        snprintf(e->target, sizeof(e->target), "%s", tok[1]);
        return NULL;
    }
    if (strcmp(kind, "pose") == 0) {
        e->type = INPUT_POSE;
        if ((n != 8 && n != 11) ||
            (strcmp(tok[1], "tracker") != 0 && strcmp(tok[1], "world") != 0))
            return "\"pose tracker|world X Y Z DX DY DZ [UX UY UZ]\"";
        e->space = strcmp(tok[1], "world") == 0 ? INPUT_SPACE_WORLD : INPUT_SPACE_TRACKER;
        for (int i = 0; i < 3; i++) {
            if (!parse_float(tok[2 + i], &e->position[i]) ||
                !parse_float(tok[5 + i], &e->direction[i]))
                return "\"pose tracker|world X Y Z DX DY DZ\" (numbers)";
        }
        float len = sqrtf(e->direction[0] * e->direction[0] + e->direction[1] * e->direction[1] +
                          e->direction[2] * e->direction[2]);
        if (!(len > 0.0f))
            return "a direction DX DY DZ that is not zero";
        /* A unit direction (as a recording writes it) is kept to the bit. */
        for (int i = 0; i < 3 && fabsf(len - 1.0f) > 1e-5f; i++)
            e->direction[i] /= len;
        if (n == 11) {
            /* The wand's up: made unit and across the direction. */
            for (int i = 0; i < 3; i++)
                if (!parse_float(tok[8 + i], &e->up[i]))
                    return "\"pose tracker|world X Y Z DX DY DZ UX UY UZ\" (numbers)";
            float d = e->up[0] * e->direction[0] + e->up[1] * e->direction[1] +
                      e->up[2] * e->direction[2];
            for (int i = 0; i < 3; i++)
                e->up[i] -= d * e->direction[i];
            float ul = sqrtf(e->up[0] * e->up[0] + e->up[1] * e->up[1] + e->up[2] * e->up[2]);
            if (!(ul > 1e-6f))
                return "an up UX UY UZ that is not zero nor along the direction";
            for (int i = 0; i < 3 && fabsf(ul - 1.0f) > 1e-5f; i++)
                e->up[i] /= ul;
            e->has_up = true;
        }
        return NULL;
    }
    if (strcmp(kind, "drag") == 0) {
        e->type = INPUT_DRAG;
        if (n != 3 || !parse_float(tok[1], &e->u) || !parse_float(tok[2], &e->v))
            return "\"drag DX DY\" (pixels right and down)";
        return NULL;
    }
    if (strcmp(kind, "scroll") == 0) {
        e->type = INPUT_SCROLL;
        if (n != 2 || !parse_float(tok[1], &e->value))
            return "\"scroll NOTCHES\"";
        return NULL;
    }
    return "an event: button, key, axis, aim, pose, drag or scroll, or a recording's time, "
           "head or cursor";
}

static bool parse_double(const char *tok, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(tok, &end);
    if (*end || end == tok || errno || !isfinite(v))
        return false;
    *out = v;
    return true;
}

/* A recording's per-frame line (time, head, cursor) into INFO.  NULL, or what was expected;
 * *HANDLED false when the words are an event instead. */
static const char *parse_frame_line(char **tok, int n, struct input_script_frame *info,
                                    bool *handled)
{
    *handled = true;
    const char *kind = tok[0];
    if (strcmp(kind, "time") == 0) {
        if (n != 3 || !parse_double(tok[1], &info->time_s) ||
            !parse_double(tok[2], &info->dt_s) || info->dt_s < 0.0 || info->dt_s > 3600.0)
            return "\"time SECONDS DT\" (the frame's clock and its step, DT in [0, 3600])";
        info->have_time = true;
        return NULL;
    }
    if (strcmp(kind, "head") == 0) {
        bool ok = n == 8;
        for (int i = 0; ok && i < 3; i++)
            ok = parse_float(tok[1 + i], &info->head_position[i]) &&
                 fabsf(info->head_position[i]) <= 1e4f;
        float len = 0.0f;
        for (int i = 0; ok && i < 4; i++) {
            ok = parse_float(tok[4 + i], &info->head_rotation[i]);
            len += info->head_rotation[i] * info->head_rotation[i];
        }
        if (!ok || fabsf(sqrtf(len) - 1.0f) > 1e-3f)
            return "\"head X Y Z QX QY QZ QW\" (room metres within 10 km, a unit quaternion)";
        info->have_head = true;
        return NULL;
    }
    if (strcmp(kind, "eyes") == 0) {
        bool ok = n == 15;
        for (int e = 0; ok && e < 2; e++) {
            float len = 0.0f;
            for (int i = 0; ok && i < 3; i++)
                ok = parse_float(tok[1 + 7 * e + i], &info->eye_position[e][i]) &&
                     fabsf(info->eye_position[e][i]) <= 1.0f;
            for (int i = 0; ok && i < 4; i++) {
                ok = parse_float(tok[4 + 7 * e + i], &info->eye_rotation[e][i]);
                len += info->eye_rotation[e][i] * info->eye_rotation[e][i];
            }
            ok = ok && fabsf(sqrtf(len) - 1.0f) <= 1e-3f;
        }
        if (!ok)
            return "\"eyes X Y Z QX QY QZ QW X Y Z QX QY QZ QW\" (the left and right eye in the "
                   "head's frame: metres within 1 m, unit quaternions)";
        info->have_eyes = true;
        return NULL;
    }
    if (strcmp(kind, "cursor") == 0) {
        char *end;
        errno = 0;
        long step = n == 4 ? strtol(tok[1], &end, 10) : -1;
        bool ok = n == 4 && !*end && !errno && step >= 0 && step < 1000000 &&
                  parse_double(tok[2], &info->step_acc) && info->step_acc >= 0.0 &&
                  info->step_acc <= 1.0 && (strcmp(tok[3], "0") == 0 || strcmp(tok[3], "1") == 0);
        if (!ok)
            return "\"cursor STEP FRACTION PLAYING\" (a step from 0, a fraction in [0, 1], "
                   "0 or 1)";
        info->step = (int)step;
        info->playing = tok[3][0] == '1';
        info->have_cursor = true;
        return NULL;
    }
    *handled = false;
    return NULL;
}

/* The per-frame record of FRAME, made if needed (frames ascend). */
static struct input_script_frame *frame_slot(struct script *sc, long frame)
{
    if (sc->frame_count && sc->frames[sc->frame_count - 1].frame == frame)
        return &sc->frames[sc->frame_count - 1].info;
    if (sc->frame_count == sc->frame_cap) {
        int cap = sc->frame_cap ? 2 * sc->frame_cap : 64;
        struct frame_info *grown = realloc(sc->frames, sizeof(*grown) * (size_t)cap);
        if (!grown)
            return NULL;
        sc->frames = grown;
        sc->frame_cap = cap;
    }
    struct frame_info *f = &sc->frames[sc->frame_count++];
    memset(f, 0, sizeof(*f));
    f->frame = frame;
    return &f->info;
}

struct input_source *input_script_open(const char *path)
{
    char *text = file_read_all(path, NULL);
    if (!text)
        return NULL;
    struct script *sc = calloc(1, sizeof(*sc));
    if (!sc) {
        free(text);
        log_error("%s: out of memory", path);
        return NULL;
    }
    sc->base.impl = &script_impl;
    sc->fps = 30.0;
    sc->menu_shown = -1;
    sc->polled = -1;
    sc->path = strdup(path);
    if (!sc->path) {
        log_error("%s: out of memory", path);
        goto error;
    }
    int cap = 0, line_no = 0;
    long last = -1;
    for (char *line = text, *next; line; line = next) {
        next = strchr(line, '\n');
        if (next)
            *next++ = '\0';
        line_no++;
        char *hash = strchr(line, '#');
        if (hash)
            *hash = '\0';
        /* The longest line is a frame's eyes (16 words); one word more makes any line wrong. */
        char *tok[17];
        int n = 0;
        char *ts = NULL;
        for (char *t = strtok_r(line, " \t\r", &ts); t && n < 17; t = strtok_r(NULL, " \t\r", &ts))
            tok[n++] = t;
        if (n == 0)
            continue;
        if (strcmp(tok[0], "recorded") == 0) {
            if (n != 2 || (strcmp(tok[1], "run") != 0 && strcmp(tok[1], "render") != 0)) {
                log_error("%s:%d: expected \"recorded run\" or \"recorded render\"", path,
                          line_no);
                goto error;
            }
            sc->recorded = true;
            sc->from_run = strcmp(tok[1], "run") == 0;
            continue;
        }
        if (strcmp(tok[0], "menu") == 0 && n == 2) {
            if (strcmp(tok[1], "shown") != 0 && strcmp(tok[1], "hidden") != 0) {
                log_error("%s:%d: expected \"menu shown\" or \"menu hidden\"", path, line_no);
                goto error;
            }
            sc->menu_shown = strcmp(tok[1], "shown") == 0;
            continue;
        }
        if (strcmp(tok[0], "fps") == 0) {
            float fps;
            if (n != 2 || !parse_float(tok[1], &fps) || !(fps > 0.0f && fps <= 1000.0f)) {
                log_error("%s:%d: expected \"fps N\" with N in (0, 1000]", path, line_no);
                goto error;
            }
            sc->fps = fps;
            continue;
        }
        char *end;
        errno = 0;
        long frame = strtol(tok[0], &end, 10);
        if (*end || errno || frame < 0 || frame > INPUT_SCRIPT_FRAMES_MAX) {
            /* A frame of 9e18 made a render play for hours. */
            log_error("%s:%d: expected a frame number from 0 to %d first, got \"%s\"", path,
                      line_no, INPUT_SCRIPT_FRAMES_MAX, tok[0]);
            goto error;
        }
        if (frame < last) {
            log_error("%s:%d: frame %ld comes before frame %ld: frames must ascend", path,
                      line_no, frame, last);
            goto error;
        }
        if (n < 2) {
            log_error("%s:%d: expected an event after the frame number", path, line_no);
            goto error;
        }
        struct input_script_frame *slot = frame_slot(sc, frame);
        if (!slot) {
            log_error("%s: out of memory", path);
            goto error;
        }
        bool handled;
        const char *expected = parse_frame_line(tok + 1, n - 1, slot, &handled);
        if (expected) {
            log_error("%s:%d: expected %s", path, line_no, expected);
            goto error;
        }
        last = frame;
        if (handled) {
            sc->has_head = sc->has_head || slot->have_head;
            continue;
        }
        struct input_event e;
        expected = parse_event(tok + 1, n - 1, &e);
        if (expected) {
            log_error("%s:%d: expected %s", path, line_no, expected);
            goto error;
        }
        if (sc->count == cap) {
            cap = cap ? 2 * cap : 64;
            struct timed_event *grown = realloc(sc->events, sizeof(*grown) * (size_t)cap);
            if (!grown) {
                log_error("%s: out of memory", path);
                goto error;
            }
            sc->events = grown;
        }
        sc->events[sc->count++] = (struct timed_event){frame, line_no, e};
        last = frame;
    }
    free(text);
    return &sc->base;

error:
    free(text);
    script_destroy(&sc->base);
    return NULL;
}

double input_script_fps(const struct input_source *s)
{
    return s->impl == &script_impl ? ((const struct script *)s)->fps : 30.0;
}

bool input_script_check_aims(const struct input_source *s,
                             bool (*known)(const char *name, void *user), void *user)
{
    if (s->impl != &script_impl)
        return true;
    const struct script *sc = (const struct script *)s;
    for (int i = 0; i < sc->count; i++) {
        const struct timed_event *t = &sc->events[i];
        if (t->event.type == INPUT_AIM && !known(t->event.target, user)) {
            log_error("%s:%d: expected a widget of the menu (docs/menu.md lists them), got "
                      "\"%s\"",
                      sc->path, t->line, t->event.target);
            return false;
        }
    }
    return true;
}

long input_script_last_frame(const struct input_source *s)
{
    if (s->impl != &script_impl)
        return -1;
    const struct script *sc = (const struct script *)s;
    long last = sc->count ? sc->events[sc->count - 1].frame : -1;
    if (sc->frame_count && sc->frames[sc->frame_count - 1].frame > last)
        last = sc->frames[sc->frame_count - 1].frame;
    return last;
}

bool input_script_frame(const struct input_source *s, long frame, struct input_script_frame *out)
{
    memset(out, 0, sizeof(*out));
    if (s->impl != &script_impl)
        return false;
    const struct script *sc = (const struct script *)s;
    int lo = 0, hi = sc->frame_count;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (sc->frames[mid].frame < frame)
            lo = mid + 1;
        else
            hi = mid;
    }
    if (lo >= sc->frame_count || sc->frames[lo].frame != frame)
        return false;
    *out = sc->frames[lo].info;
    return out->have_time || out->have_head || out->have_eyes || out->have_cursor;
}

bool input_script_has_head(const struct input_source *s)
{
    return s->impl == &script_impl && ((const struct script *)s)->has_head;
}

bool input_script_recorded(const struct input_source *s, bool *from_run, int *menu_shown)
{
    const struct script *sc = s->impl == &script_impl ? (const struct script *)s : NULL;
    if (from_run)
        *from_run = sc && sc->from_run;
    if (menu_shown)
        *menu_shown = sc ? sc->menu_shown : -1;
    return sc && sc->recorded;
}
