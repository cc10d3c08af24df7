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

#include "common/log.h"
#include "display/display_impl.h"
#include "shaders/bindings.h"

static const struct display_impl *const backends[] = {
    &display_headless_impl, &display_desktop_impl, &display_stereo_impl,
    &display_cave_impl,     &display_hmd_impl,
};

#define BACKEND_COUNT ((int)(sizeof(backends) / sizeof(backends[0])))

void display_list(void (*print)(const char *name, const char *what, void *user), void *user)
{
    for (int i = 0; i < BACKEND_COUNT; i++)
        print(backends[i]->name, backends[i]->description, user);
}

struct display *display_create(const struct display_config *cfg, const struct display_desc *desc)
{
    const char *name = display_type_name(cfg->type);
    const struct display_impl *impl = NULL;
    for (int i = 0; i < BACKEND_COUNT; i++) {
        if (strcmp(backends[i]->name, name) == 0)
            impl = backends[i];
    }
    if (!impl) {
        log_error("%s: no display backend \"%s\"", cfg->path, name);
        return NULL;
    }
    struct display base = {.impl = impl, .cfg = *cfg};
    if (desc)
        base.desc = *desc;
    if (base.desc.height < 1)
        base.desc.height = 480;
    struct display *d = impl->create(&base);
    if (!d)
        return NULL;
    /* The HMD backend reads its own device's pose; everything else uses the tracker. */
    bool own_pose = impl == &display_hmd_impl && cfg->head.source == DISPLAY_HEAD_OPENHMD;
    struct display_head head_cfg = cfg->head;
    if (own_pose)
        head_cfg.source = DISPLAY_HEAD_FIXED;
    if (!display_head_tracker_init(&d->head, &head_cfg))
        goto error;
    if (!gpu_program_init(&d->compose, "display_compose.comp", NULL))
        goto error;
    if (!display_update(d, 0.0))
        goto error;
    return d;

error:
    display_destroy(d);
    return NULL;
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

bool display_update(struct display *d, double t)
{
    struct display_pose head;
    d->time = t;
    if (!display_head_tracker_pose(&d->head, t, &head))
        return false;
    return d->impl->layout(d, &head);
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
    if (d->desc.offscreen && d->desc.context) {
        d->context = d->desc.context;
        d->own_context = false;
        gpu_context_make_current(d->context);
        return true;
    }
    struct gpu_context_desc cd = {.backend = "egl", .monitor = -1};
    if (!d->desc.offscreen) {
        cd.backend = "glfw";
        cd.width = w;
        cd.height = h;
        cd.monitor = monitor;
        cd.stereo = stereo;
        cd.title = title;
    }
    d->context = gpu_context_create(&cd);
    d->own_context = d->context != NULL;
    if (d->context && !d->desc.offscreen)
        display_watch_window(d, gpu_context_window(d->context));
    return d->context != NULL;
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

/* ---- windows: close keys and flying ---------------------------------------------------- */

static void on_key(GLFWwindow *w, int key, int scancode, int action, int mods)
{
    struct display *d = glfwGetWindowUserPointer(w);
    if (!d || action == GLFW_RELEASE)
        return;
    struct display_navigation *nav = &d->cfg.navigation;
    const double step = 0.1; /* tracker metres per key press */
    switch (key) {
    case GLFW_KEY_ESCAPE:
    case GLFW_KEY_Q:
        d->should_close = true;
        return;
    case GLFW_KEY_W: /* fly forward: the world comes toward the viewer */
        nav->position[2] += step;
        break;
    case GLFW_KEY_S:
        nav->position[2] -= step;
        break;
    case GLFW_KEY_A:
        nav->position[0] += step;
        break;
    case GLFW_KEY_D:
        nav->position[0] -= step;
        break;
    case GLFW_KEY_PAGE_UP:
    case GLFW_KEY_R:
        nav->position[1] -= step;
        break;
    case GLFW_KEY_PAGE_DOWN:
    case GLFW_KEY_F:
        nav->position[1] += step;
        break;
    case GLFW_KEY_LEFT:
        nav->orientation_deg[0] = fmod(nav->orientation_deg[0] - 5.0, 360.0);
        break;
    case GLFW_KEY_RIGHT:
        nav->orientation_deg[0] = fmod(nav->orientation_deg[0] + 5.0, 360.0);
        break;
    case GLFW_KEY_EQUAL:
    case GLFW_KEY_KP_ADD:
        nav->scale *= 1.25;
        break;
    case GLFW_KEY_MINUS:
    case GLFW_KEY_KP_SUBTRACT:
        nav->scale /= 1.25;
        break;
    default:
        return;
    }
    d->nav_changed = true;
}

void display_watch_window(struct display *d, void *window)
{
    glfwSetWindowUserPointer(window, d);
    glfwSetKeyCallback(window, on_key);
}

void display_poll(struct display *d, double timeout_s)
{
    if (timeout_s > 0.0)
        glfwWaitEventsTimeout(timeout_s);
    else
        glfwPollEvents();
}

bool display_should_close(const struct display *d)
{
    return d->should_close;
}

struct display_navigation *display_navigation(struct display *d)
{
    return &d->cfg.navigation;
}

bool display_navigation_changed(struct display *d)
{
    bool changed = d->nav_changed;
    d->nav_changed = false;
    return changed;
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
    snprintf(path, sizeof(path), "%s/%s.%s", dir, name, ext);
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
        if (ok && display_contact_sheet(images, n, walls, 2, bg, &sheet)) {
            char path[1200];
            snprintf(path, sizeof(path), "%s/contact.%s", dir, ext);
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
