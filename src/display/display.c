/*
 * What every display shares: the backend table, the head tracker, the frame loop over views,
 * stereo composition, showing in windows, keyboard flying and the image files.
 */
#include "display/display.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <GLFW/glfw3.h>
#include <cglm/cglm.h>

#include "common/log.h"
#include "common/mat4d.h"
#include "display/display_impl.h"
#include "shaders/bindings.h"

static const struct display_impl *const backends[] = {
    &display_headless_impl, &display_desktop_impl, &display_stereo_impl,
    &display_cave_impl,     &display_hmd_impl,     &display_orbit_impl,
#if HAVE_OPENXR
    &display_openxr_impl,
#endif
};

#define BACKEND_COUNT ((int)(sizeof(backends) / sizeof(backends[0])))

void display_list(void (*print)(const char *name, const char *what, void *user), void *user)
{
    for (int i = 0; i < BACKEND_COUNT; i++)
        print(backends[i]->name, backends[i]->description, user);
}

static const struct display_impl *find_backend(enum display_type type)
{
    const char *name = display_type_name(type);
    for (int i = 0; i < BACKEND_COUNT; i++) {
        if (strcmp(backends[i]->name, name) == 0)
            return backends[i];
    }
    return NULL;
}

bool display_type_available(enum display_type type)
{
    return find_backend(type) != NULL;
}

struct display *display_create(const struct display_config *cfg, const struct display_desc *desc)
{
    const struct display_impl *impl = find_backend(cfg->type);
    if (desc && desc->failure)
        *desc->failure = DISPLAY_FAILED_NONE;
    if (!impl) {
        log_error("%s: no display backend \"%s\" in this build", cfg->path,
                  display_type_name(cfg->type));
        if (desc && desc->failure)
            *desc->failure = DISPLAY_FAILED_INPUT;
        return NULL;
    }
    struct display base = {.impl = impl, .cfg = *cfg};
    if (desc)
        base.desc = *desc;
    if (base.desc.height < 1)
        base.desc.height = 480;
    struct display *d = impl->create(&base);
    if (!d) {
        display_fail(&base, DISPLAY_FAILED_OTHER); /* unless the backend said why */
        return NULL;
    }
    /* A head the caller gives opens no tracker (a cluster's rank 0 samples it for all). */
    struct display_head head = cfg->head;
    if (d->desc.head_given)
        head.source = DISPLAY_HEAD_FIXED;
    if (!display_head_tracker_init(&d->head, &head, cfg)) {
        display_fail(d, DISPLAY_FAILED_INPUT); /* a pose file, a tracker device */
        goto error;
    }
    if (!gpu_program_init(&d->compose, "display_compose.comp", NULL))
        goto error;
    if (!display_update(d, 0.0))
        goto error;
    return d;

error:
    display_fail(d, DISPLAY_FAILED_OTHER);
    display_destroy(d);
    return NULL;
}

void display_fail(const struct display *d, enum display_failure why)
{
    if (d->desc.failure && *d->desc.failure == DISPLAY_FAILED_NONE)
        *d->desc.failure = why;
}

void display_destroy(struct display *d)
{
    if (!d)
        return;
    if (d->context)
        gpu_context_make_current(d->context);
    view_set_finish(&d->set);
    for (int i = 0; i < DISPLAY_MAX_OUTPUTS; i++)
        gpu_texture_finish(&d->outputs[i].hdr);
    gpu_program_finish(&d->compose);
    display_head_tracker_finish(&d->head);
    d->impl->destroy(d); /* closes windows and contexts, frees D */
}

struct gpu_context *display_context(struct display *d)
{
    return d->context;
}

const struct display_config *display_get_config(const struct display *d)
{
    return &d->cfg;
}

bool display_sample_head(struct display *d, double t, struct display_pose *head)
{
    d->time = t;
    if (d->impl->sample_head)
        return d->impl->sample_head(d, t, head);
    return display_head_tracker_pose(&d->head, t, head);
}

bool display_layout(struct display *d, const struct display_pose *head,
                    const struct display_navigation *nav, const struct display_camera *camera)
{
    return d->impl->layout(d, head, nav, camera);
}

bool display_update(struct display *d, double t)
{
    struct display_pose head;
    return display_sample_head(d, t, &head) &&
           display_layout(d, &head, &d->cfg.navigation, &d->desc.camera);
}

bool display_uses_camera(const struct display *d)
{
    return d->impl == &display_orbit_impl;
}

bool display_paces_frames(const struct display *d)
{
    return d->impl->sample_head != NULL;
}

bool display_eyes_in_head(const struct display *d, struct display_pose out[2])
{
    return d->impl->eyes_in_head && d->impl->eyes_in_head(d, out);
}

void display_give_eyes(struct display *d, const struct display_pose eyes[2])
{
    if (d->impl->give_eyes)
        d->impl->give_eyes(d, eyes);
}

bool display_head_moves(const struct display *d)
{
    return d->cfg.head.source != DISPLAY_HEAD_FIXED || d->impl->sample_head != NULL;
}

int display_view_count(const struct display *d)
{
    return d->set.count;
}

struct view *display_view(struct display *d, int i)
{
    return i >= 0 && i < d->set.count ? &d->set.views[i] : NULL;
}

bool display_draw(struct display *d, struct renderer *r, const struct render_settings *s)
{
    gpu_context_make_current(d->context);
    for (int i = 0; i < d->set.count; i++) {
        struct view *v = &d->set.views[i];
        if (v->visible && !renderer_draw(r, s, &v->rv, &v->target))
            return false;
    }
    return true;
}

bool display_present(struct display *d, struct renderer *r, float exposure)
{
    gpu_context_make_current(d->context);
    return d->impl->present(d, r, exposure);
}

int display_output_count(const struct display *d)
{
    return d->output_count;
}

const struct gpu_texture *display_output(const struct display *d, int i, const char **name)
{
    if (i < 0 || i >= d->output_count)
        return NULL;
    if (name)
        *name = d->outputs[i].name;
    return &d->outputs[i].hdr;
}

/* ---- shared by backends -------------------------------------------------------------- */

bool display_open_primary(struct display *d, int w, int h, int monitor, bool stereo,
                          const char *title)
{
    return display_open_primary_on(d, &(struct gpu_context_desc){.width = w,
                                                                 .height = h,
                                                                 .monitor = monitor,
                                                                 .stereo = stereo,
                                                                 .title = title});
}

bool display_open_primary_on(struct display *d, const struct gpu_context_desc *window)
{
    if (d->desc.offscreen && d->desc.context) {
        d->context = d->desc.context;
        d->own_context = false;
        gpu_context_make_current(d->context);
        return true;
    }
    struct gpu_context_desc cd = {.backend = "egl", .monitor = -1, .device = d->desc.gpu_device};
    if (!d->desc.offscreen) {
        cd = *window;
        cd.backend = "glfw";
    }
    d->context = gpu_context_create(&cd);
    d->own_context = d->context != NULL;
    if (d->context && !d->desc.offscreen) {
        display_watch_window(d, gpu_context_window(d->context));
        display_join_swap_group(d, d->context);
    }
    if (!d->context)
        display_fail(d, DISPLAY_FAILED_CONTEXT);
    return d->context != NULL;
}

void display_join_swap_group(struct display *d, struct gpu_context *ctx)
{
    if (!d->desc.swap_group)
        return;
    d->swap_windows++;
    if (gpu_context_join_swap_group(ctx, d->desc.swap_group, d->desc.swap_group))
        d->swap_joined++;
    gpu_context_make_current(d->context);
}

bool display_swap_grouped(const struct display *d)
{
    return d->swap_windows > 0 && d->swap_joined == d->swap_windows;
}

void display_close_primary(struct display *d)
{
    if (d->own_context)
        gpu_context_destroy(d->context);
    d->context = NULL;
}

void display_offscreen_sizes(const struct display *d, int (*sizes)[2])
{
    for (int w = 0; w < d->cfg.wall_count; w++)
        view_set_wall_size(&d->cfg, w, d->desc.height, sizes[w]);
}

struct display_output *display_output_ensure(struct display *d, int i, const char *name, int w,
                                             int h)
{
    struct display_output *o = &d->outputs[i];
    snprintf(o->name, sizeof(o->name), "%s", name);
    if (!o->hdr.id || o->hdr.size[0] != w || o->hdr.size[1] != h) {
        gpu_texture_finish(&o->hdr);
        int size[3] = {w, h, 1};
        if (!gpu_texture_init(&o->hdr, 2, size, GPU_RGBA32F, NULL))
            return NULL;
    }
    if (d->output_count <= i)
        d->output_count = i + 1;
    return o;
}

bool display_compose(struct display *d, const struct gpu_texture *left,
                     const struct gpu_texture *right, int mode, struct gpu_texture *out, int x,
                     int y)
{
    if (!left->id || (mode == 1 && (!right->id || right->size[0] != left->size[0] ||
                                    right->size[1] != left->size[1]))) {
        log_error("stereo composition: eye images missing or of different sizes");
        return false;
    }
    int size[2] = {left->size[0], left->size[1]}, offset[2] = {x, y};
    gpu_uniform_int(&d->compose, "mode", mode);
    gpu_uniform_ivec2(&d->compose, "size", size);
    gpu_uniform_ivec2(&d->compose, "offset", offset);
    gpu_texture_bind(left, BIND_COMPOSE_TEX_LEFT);
    gpu_texture_bind(mode == 1 ? right : left, BIND_COMPOSE_TEX_RIGHT);
    gpu_image_bind(out, BIND_COMPOSE_IMG_OUT, true);
    gpu_dispatch(&d->compose, size[0], size[1], 1);
    return true;
}

bool display_show(struct renderer *r, const struct gpu_texture *in, float exposure,
                  struct gpu_texture *scratch, int x, int y, int w, int h, int buffer)
{
    if (!renderer_tonemap(r, in, exposure, scratch))
        return false;
    gpu_present(scratch, x, y, w, h, buffer);
    return true;
}

void display_before_swap(struct display *d)
{
    if (d->desc.before_swap)
        d->desc.before_swap(d->desc.swap_user);
}

bool display_show_window(struct display *d, struct renderer *r, const struct gpu_texture *in,
                         float exposure, struct gpu_texture *scratch)
{
    int fw, fh;
    gpu_context_size(d->context, &fw, &fh);
    if (!display_show(r, in, exposure, scratch, 0, 0, fw, fh, 0))
        return false;
    display_before_swap(d);
    gpu_context_swap(d->context);
    return true;
}

/* ---- windows: the one key table, and window events as input events -------------------- */

/* A key held with Shift (SHIFTED(GLFW_KEY_F)): an entry of its own; without one the key means
 * what it means alone. */
#define SHIFTED(k) ((k) | 0x10000)

/* A window key, what it means everywhere, and whether holding it repeats. */
static const struct {
    int glfw;
    enum input_key key;
    bool repeats;
    const char *label;
} keys[] = {
    {GLFW_KEY_W, INPUT_KEY_MOVE_FORWARD, true, "W"},
    {GLFW_KEY_S, INPUT_KEY_MOVE_BACK, true, "S"},
    {GLFW_KEY_A, INPUT_KEY_MOVE_LEFT, true, "A"},
    {GLFW_KEY_D, INPUT_KEY_MOVE_RIGHT, true, "D"},
    {GLFW_KEY_R, INPUT_KEY_MOVE_UP, true, "R"},
    {GLFW_KEY_PAGE_UP, INPUT_KEY_MOVE_UP, true, "Page Up"},
    {GLFW_KEY_F, INPUT_KEY_MOVE_DOWN, true, "F"},
    {GLFW_KEY_PAGE_DOWN, INPUT_KEY_MOVE_DOWN, true, "Page Down"},
    {GLFW_KEY_LEFT, INPUT_KEY_TURN_LEFT, true, "Left"},
    {GLFW_KEY_RIGHT, INPUT_KEY_TURN_RIGHT, true, "Right"},
    {GLFW_KEY_UP, INPUT_KEY_TURN_UP, true, "Up"},
    {GLFW_KEY_DOWN, INPUT_KEY_TURN_DOWN, true, "Down"},
    {GLFW_KEY_EQUAL, INPUT_KEY_ZOOM_IN, true, "+"},
    {GLFW_KEY_KP_ADD, INPUT_KEY_ZOOM_IN, true, "keypad +"},
    {GLFW_KEY_MINUS, INPUT_KEY_ZOOM_OUT, true, "-"},
    {GLFW_KEY_KP_SUBTRACT, INPUT_KEY_ZOOM_OUT, true, "keypad -"},
    {GLFW_KEY_J, INPUT_KEY_SUN_LEFT, true, "J"},
    {GLFW_KEY_L, INPUT_KEY_SUN_RIGHT, true, "L"},
    {GLFW_KEY_I, INPUT_KEY_SUN_UP, true, "I"},
    {GLFW_KEY_K, INPUT_KEY_SUN_DOWN, true, "K"},
    {GLFW_KEY_P, INPUT_KEY_SCREENSHOT, false, "P"},
    {GLFW_KEY_C, INPUT_KEY_BOOKMARK, false, "C"},
    {GLFW_KEY_N, INPUT_KEY_PATH_KEY, false, "N"},
    {GLFW_KEY_G, INPUT_KEY_PATH_PLAY, false, "G"},
    {GLFW_KEY_V, INPUT_KEY_PROBE, false, "V"},
    {GLFW_KEY_SPACE, INPUT_KEY_PLAY, false, "Space"},
    {GLFW_KEY_COMMA, INPUT_KEY_STEP_BACK, true, ","},
    {GLFW_KEY_PERIOD, INPUT_KEY_STEP_FORWARD, true, "."},
    {GLFW_KEY_TAB, INPUT_KEY_MENU, false, "Tab"},
    {GLFW_KEY_M, INPUT_KEY_MENU, false, "M"},
    {GLFW_KEY_RIGHT_BRACKET, INPUT_KEY_PAGE_NEXT, false, "]"},
    {GLFW_KEY_LEFT_BRACKET, INPUT_KEY_PAGE_PREV, false, "["},
    {GLFW_KEY_ESCAPE, INPUT_KEY_QUIT, false, "Esc"},
    {GLFW_KEY_Q, INPUT_KEY_QUIT, false, "Q"},
    {SHIFTED(GLFW_KEY_F), INPUT_KEY_FRAME, false, "Shift+F"},
};

#define KEY_COUNT ((int)(sizeof(keys) / sizeof(keys[0])))

void display_list_keys(void (*print)(const char *keys, enum input_key key, void *user),
                       void *user)
{
    /* One line per meaning, its keys joined: "R, Page Up". */
    for (int i = 0; i < KEY_COUNT; i++) {
        bool first = true;
        for (int j = 0; j < i; j++)
            first = first && keys[j].key != keys[i].key;
        if (!first)
            continue;
        char labels[64] = "";
        size_t len = 0;
        for (int j = i; j < KEY_COUNT; j++) {
            if (keys[j].key == keys[i].key)
                len += (size_t)snprintf(labels + len, sizeof(labels) - len, "%s%s",
                                        len ? ", " : "", keys[j].label);
        }
        print(labels, keys[i].key, user);
    }
}

static void push(struct display *d, const struct input_event *e)
{
    input_queue_push(&d->pending, e);
}

static void push_button(struct display *d, enum input_button b, bool down)
{
    push(d, &(struct input_event){.type = INPUT_BUTTON, .button = b, .down = down});
}

static void on_key(GLFWwindow *w, int key, int scancode, int action, int mods)
{
    struct display *d = glfwGetWindowUserPointer(w);
    if (!d || action == GLFW_RELEASE)
        return;
    if (key == GLFW_KEY_HOME && action == GLFW_PRESS) {
        push_button(d, INPUT_BUTTON_RESET, true);
        push_button(d, INPUT_BUTTON_RESET, false);
        return;
    }
    int shifted = SHIFTED(key);
    bool has_shifted = false;
    for (int i = 0; i < KEY_COUNT; i++)
        has_shifted = has_shifted || keys[i].glfw == shifted;
    int code = (mods & GLFW_MOD_SHIFT) && has_shifted ? shifted : key;
    for (int i = 0; i < KEY_COUNT; i++) {
        if (keys[i].glfw == code && (action == GLFW_PRESS || keys[i].repeats)) {
            push(d, &(struct input_event){.type = INPUT_KEY, .key = keys[i].key});
            return;
        }
    }
}

static void on_button(GLFWwindow *w, int button, int action, int mods)
{
    struct display *d = glfwGetWindowUserPointer(w);
    if (!d)
        return;
    bool down = action == GLFW_PRESS;
    if (button == GLFW_MOUSE_BUTTON_LEFT) {
        push_button(d, INPUT_BUTTON_TRIGGER, down);
        d->dragging = down;
        glfwGetCursorPos(w, &d->drag_from[0], &d->drag_from[1]);
    } else if (button == GLFW_MOUSE_BUTTON_MIDDLE) {
        push_button(d, INPUT_BUTTON_GRAB, down);
    } else if (button == GLFW_MOUSE_BUTTON_RIGHT && down) {
        push(d, &(struct input_event){.type = INPUT_KEY, .key = INPUT_KEY_MENU});
    }
}

static void on_cursor(GLFWwindow *w, double x, double y)
{
    struct display *d = glfwGetWindowUserPointer(w);
    if (!d)
        return;
    d->cursor[0] = x;
    d->cursor[1] = y;
    if (!d->dragging)
        return;
    push(d, &(struct input_event){.type = INPUT_DRAG, .u = (float)(x - d->drag_from[0]),
                                  .v = (float)(y - d->drag_from[1])});
    d->drag_from[0] = x;
    d->drag_from[1] = y;
}

static void on_scroll(GLFWwindow *w, double dx, double dy)
{
    struct display *d = glfwGetWindowUserPointer(w);
    if (d && dy != 0.0)
        push(d, &(struct input_event){.type = INPUT_SCROLL, .value = (float)dy});
}

static void on_close(GLFWwindow *w)
{
    struct display *d = glfwGetWindowUserPointer(w);
    if (!d)
        return;
    d->should_close = true;
    push(d, &(struct input_event){.type = INPUT_KEY, .key = INPUT_KEY_QUIT});
}

void display_watch_window(struct display *d, void *window)
{
    glfwSetWindowUserPointer(window, d);
    glfwSetKeyCallback(window, on_key);
    glfwSetMouseButtonCallback(window, on_button);
    glfwSetCursorPosCallback(window, on_cursor);
    glfwSetScrollCallback(window, on_scroll);
    glfwSetWindowCloseCallback(window, on_close);
}

static void unproject(const double m[16], double x, double y, double z, double out[3])
{
    double v[4];
    for (int r = 0; r < 4; r++)
        v[r] = m[r] * x + m[4 + r] * y + m[8 + r] * z + m[12 + r];
    for (int i = 0; i < 3; i++)
        out[i] = v[i] / v[3];
}

/* The ray through the pointer in the first view, world space: the desktop wand.  The inverse
 * view-projection in double, as the eye pass's rays (common/mat4d): a float one puts a pick
 * at long range (far / near ~1e5) off the cloud under the pointer.  Pushed when the pointer,
 * the window or the view moved since the last push, not every frame: a script's `aim` (or a
 * recording's pose) holds until then, instead of being taken back by a pointer that did not
 * move before its trigger acts. */
static void push_pointer(struct display *d, struct input_queue *q)
{
    if (d->set.count < 1 || !(d->impl == &display_orbit_impl || d->impl == &display_desktop_impl ||
                              d->impl == &display_stereo_impl))
        return;
    const struct view *v = &d->set.views[0];
    int ww, wh;
    glfwGetWindowSize(gpu_context_window(d->context), &ww, &wh);
    if (ww <= 0 || wh <= 0)
        return;
    double vp[16], inv[16];
    for (int c = 0; c < 4; c++) /* column-major: vp = proj * view */
        for (int r = 0; r < 4; r++) {
            double sum = 0.0;
            for (int k = 0; k < 4; k++)
                sum += (double)v->rv.proj[4 * k + r] * (double)v->rv.view[4 * c + k];
            vp[4 * c + r] = sum;
        }
    if (d->pointer_sent && d->pointer_cursor[0] == d->cursor[0] &&
        d->pointer_cursor[1] == d->cursor[1] && d->pointer_window[0] == ww &&
        d->pointer_window[1] == wh && memcmp(d->pointer_vp, vp, sizeof(vp)) == 0)
        return;
    if (!mat4d_invert(vp, inv))
        return;
    d->pointer_sent = true;
    memcpy(d->pointer_cursor, d->cursor, sizeof(d->pointer_cursor));
    memcpy(d->pointer_vp, vp, sizeof(vp));
    d->pointer_window[0] = ww;
    d->pointer_window[1] = wh;
    double x = (d->cursor[0] + 0.5) / ww * 2.0 - 1.0;
    double y = 1.0 - (d->cursor[1] + 0.5) / wh * 2.0;
    double o[3], far[3], dir[3], len = 0.0;
    unproject(inv, x, y, -1.0, o);
    unproject(inv, x, y, 1.0, far);
    for (int i = 0; i < 3; i++) {
        dir[i] = far[i] - o[i];
        len += dir[i] * dir[i];
    }
    len = sqrt(len);
    if (!(len > 0.0) || !isfinite(len))
        return;
    struct input_event e = {.type = INPUT_POSE, .space = INPUT_SPACE_WORLD};
    for (int i = 0; i < 3; i++) {
        e.position[i] = (float)o[i];
        e.direction[i] = (float)(dir[i] / len);
    }
    input_queue_push(q, &e);
}

static void poll_joystick(struct display *d, struct input_queue *q)
{
    if (!glfwJoystickPresent(GLFW_JOYSTICK_1))
        return;
    int nb = 0, na = 0;
    const unsigned char *buttons = glfwGetJoystickButtons(GLFW_JOYSTICK_1, &nb);
    const float *axes = glfwGetJoystickAxes(GLFW_JOYSTICK_1, &na);
    for (int b = 0; b < INPUT_BUTTON_COUNT && b < nb; b++) {
        if (buttons[b] != d->joy_buttons[b]) {
            d->joy_buttons[b] = buttons[b];
            input_queue_push(q, &(struct input_event){.type = INPUT_BUTTON,
                                                      .button = (enum input_button)b,
                                                      .down = buttons[b] == GLFW_PRESS});
        }
    }
    /* Left stick: up flies forward, sideways turns. */
    float want[INPUT_AXIS_COUNT] = {na > 1 ? -axes[1] : 0.0f, na > 0 ? axes[0] : 0.0f};
    for (int a = 0; a < INPUT_AXIS_COUNT; a++) {
        float v = fabsf(want[a]) < 0.15f ? 0.0f : want[a]; /* dead zone */
        if (v != d->joy_axes[a]) {
            d->joy_axes[a] = v;
            input_queue_push(q, &(struct input_event){.type = INPUT_AXIS,
                                                      .axis = (enum input_axis)a, .value = v});
        }
    }
}

void display_poll_input(struct display *d, double timeout_s, struct input_queue *q)
{
    if (d->impl->poll_input)
        d->impl->poll_input(d, timeout_s, q);
    if (d->desc.offscreen || !gpu_context_window(d->context))
        return;
    if (timeout_s > 0.0)
        glfwWaitEventsTimeout(timeout_s);
    else
        glfwPollEvents();
    /* The pose first, then what the callbacks saw, so a click acts where the pointer is. */
    push_pointer(d, q);
    for (int i = 0; i < d->pending.count; i++)
        input_queue_push(q, &d->pending.events[i]);
    q->dropped += d->pending.dropped;
    input_queue_clear(&d->pending);
    poll_joystick(d, q);
}

bool display_should_close(const struct display *d)
{
    return d->should_close;
}

/* ---- files --------------------------------------------------------------------------- */

static bool make_dir(const char *dir)
{
    char path[1024];
    snprintf(path, sizeof(path), "%s", dir);
    for (char *p = path + 1; *p; p++) {
        if (*p != '/')
            continue;
        *p = '\0';
        if (mkdir(path, 0777) != 0 && errno != EEXIST) {
            log_error("%s: cannot create the folder: %s", path, strerror(errno));
            return false;
        }
        *p = '/';
    }
    if (mkdir(path, 0777) != 0 && errno != EEXIST) {
        log_error("%s: cannot create the folder: %s", path, strerror(errno));
        return false;
    }
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISDIR(st.st_mode)) {
        log_error("%s: not a folder", path);
        return false;
    }
    return true;
}

static bool write_texture(const struct gpu_texture *tex, const char *dir, const char *name,
                          const char *ext, float exposure, struct image *keep, size_t *nonfinite)
{
    struct image img = {0};
    if (!renderer_read(tex, &img))
        return false;
    if (nonfinite)
        *nonfinite += image_count_nonfinite(&img);
    char path[1200];
    size_t dl = strlen(dir);
    snprintf(path, sizeof(path), "%s%s%s.%s", dir, dl > 0 && dir[dl - 1] == '/' ? "" : "/", name,
             ext); /* "-o out/" writes out/front-left.png, not out//front-left.png */
    bool ok = image_write(&img, path, exposure);
    if (ok)
        log_info("wrote %s (%dx%d)", path, img.width, img.height);
    if (ok && keep)
        *keep = img;
    else
        image_finish(&img);
    return ok;
}

bool display_contact_sheet(const struct image *images, int n, int columns, int gap,
                           const float background[4], struct image *out)
{
    memset(out, 0, sizeof(*out));
    if (n < 1 || columns < 1)
        return false;
    int rows = (n + columns - 1) / columns;
    int cell_w = 0, cell_h = 0;
    for (int i = 0; i < n; i++) {
        if (images[i].width > cell_w)
            cell_w = images[i].width;
        if (images[i].height > cell_h)
            cell_h = images[i].height;
    }
    int w = columns * cell_w + (columns + 1) * gap, h = rows * cell_h + (rows + 1) * gap;
    if (!image_init(out, w, h))
        return false;
    for (int i = 0; i < w * h; i++)
        memcpy(&out->rgba[4 * i], background, sizeof(float) * 4);
    for (int i = 0; i < n; i++) {
        int row = i / columns, col = i % columns;
        int x = gap + col * (cell_w + gap);
        int y = h - (row + 1) * (cell_h + gap); /* row 0 at the top */
        image_blit(out, &images[i], x, y);
    }
    return true;
}

bool display_write_images(struct display *d, const char *dir, const char *ext, float exposure,
                          size_t *nonfinite)
{
    if (!make_dir(dir))
        return false;
    gpu_context_make_current(d->context);
    if (nonfinite)
        *nonfinite = 0;
    struct image images[DISPLAY_MAX_VIEWS];
    memset(images, 0, sizeof(images));
    int order[DISPLAY_MAX_VIEWS], n = 0;
    bool ok = true;
    /* Sheet: one column per wall, one row per eye (mono walls in the first row). */
    int walls = 0;
    for (int i = 0; i < d->set.count; i++) {
        if (d->set.views[i].wall + 1 > walls)
            walls = d->set.views[i].wall + 1;
    }
    for (int eye_row = 0; eye_row < 2; eye_row++) {
        for (int w = 0; w < walls; w++) {
            int found = -1;
            for (int i = 0; i < d->set.count; i++) {
                const struct view *v = &d->set.views[i];
                int row = v->eye == VIEW_EYE_RIGHT ? 1 : 0;
                if (v->wall == w && row == eye_row)
                    found = i;
            }
            order[n++] = found;
        }
    }
    bool any_right = false;
    for (int i = 0; i < d->set.count; i++)
        any_right = any_right || d->set.views[i].eye == VIEW_EYE_RIGHT;
    if (!any_right)
        n = walls;
    for (int k = 0; k < n && ok; k++) {
        if (order[k] < 0)
            continue;
        const struct view *v = &d->set.views[order[k]];
        if (!v->target.id) {
            log_warn("view %s was not drawn (the eye is behind its wall)", v->name);
            continue;
        }
        ok = write_texture(&v->target, dir, v->name, ext, exposure, &images[k], nonfinite);
    }
    for (int i = 0; i < d->output_count && ok; i++)
        ok = write_texture(&d->outputs[i].hdr, dir, d->outputs[i].name, ext, exposure, NULL,
                           NULL);
    if (ok) {
        /* Empty cells (no view) become blank images of the first view's size. */
        int cw = 1, ch = 1;
        for (int k = 0; k < n; k++) {
            if (images[k].rgba) {
                cw = images[k].width;
                ch = images[k].height;
                break;
            }
        }
        for (int k = 0; k < n && ok; k++) {
            if (!images[k].rgba) {
                ok = image_init(&images[k], cw, ch);
                if (ok)
                    memset(images[k].rgba, 0, sizeof(float) * 4 * (size_t)cw * (size_t)ch);
            }
        }
        struct image sheet = {0};
        const float bg[4] = {0.0f, 0.0f, 0.0f, 1.0f};
        if (ok && !d->desc.partial && display_contact_sheet(images, n, walls, 2, bg, &sheet)) {
            char path[1200];
            size_t dl = strlen(dir);
            snprintf(path, sizeof(path), "%s%scontact.%s", dir,
                     dl > 0 && dir[dl - 1] == '/' ? "" : "/", ext);
            ok = image_write(&sheet, path, exposure);
            if (ok)
                log_info("wrote %s (%dx%d, %d views)", path, sheet.width, sheet.height,
                         d->set.count);
        }
        image_finish(&sheet);
    }
    for (int k = 0; k < n; k++)
        image_finish(&images[k]);
    return ok;
}
