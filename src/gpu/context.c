#include <stdio.h>
#include <string.h>
#include <strings.h>

#include <epoxy/gl.h>

#include "common/log.h"
#include "gpu/context_impl.h"

static const struct gpu_context_impl *const backends[] = {
    &gpu_context_egl_impl,
    &gpu_context_glfw_impl,
};

struct gpu_context *gpu_context_create(const struct gpu_context_desc *desc)
{
    struct gpu_context_desc d = {0};
    if (desc)
        d = *desc;
    const char *name = d.backend ? d.backend : "egl";
    for (size_t i = 0; i < sizeof(backends) / sizeof(backends[0]); i++) {
        if (strcmp(backends[i]->name, name) != 0)
            continue;
        struct gpu_context *ctx = backends[i]->create(&d);
        if (!ctx)
            return NULL;
        ctx->impl = backends[i];
        if (!gpu_context_setup_current(ctx, !d.no_debug)) {
            gpu_context_destroy(ctx);
            return NULL;
        }
        return ctx;
    }
    log_error("unknown GPU context backend \"%s\" (expected \"egl\" or \"glfw\")", name);
    return NULL;
}

void gpu_context_destroy(struct gpu_context *ctx)
{
    if (ctx)
        ctx->impl->destroy(ctx);
}

void gpu_context_make_current(struct gpu_context *ctx)
{
    ctx->impl->make_current(ctx);
}

const char *gpu_context_backend(const struct gpu_context *ctx)
{
    return ctx->impl->name;
}

void gpu_context_list(void (*print)(const char *name, const char *what, void *user), void *user)
{
    for (size_t i = 0; i < sizeof(backends) / sizeof(backends[0]); i++)
        print(backends[i]->name, backends[i]->description, user);
}

void *gpu_context_window(struct gpu_context *ctx)
{
    return ctx->impl->window ? ctx->impl->window(ctx) : NULL;
}

bool gpu_context_has_stereo(const struct gpu_context *ctx)
{
    return ctx->stereo;
}

void gpu_context_swap(struct gpu_context *ctx)
{
    if (ctx->impl->swap)
        ctx->impl->swap(ctx);
}

void gpu_context_swap_interval(struct gpu_context *ctx, int interval)
{
    if (!ctx || !ctx->impl->swap_interval)
        return;
    gpu_context_make_current(ctx);
    ctx->impl->swap_interval(ctx, interval);
}

bool gpu_context_join_swap_group(struct gpu_context *ctx, unsigned group, unsigned barrier)
{
    if (!ctx || !ctx->impl->join_swap_group)
        return false;
    gpu_context_make_current(ctx);
    return ctx->impl->join_swap_group(ctx, group, barrier);
}

void gpu_context_size(struct gpu_context *ctx, int *width, int *height)
{
    if (ctx->impl->size) {
        ctx->impl->size(ctx, width, height);
    } else {
        *width = ctx->width;
        *height = ctx->height;
    }
}

static void GLAPIENTRY debug_callback(GLenum source, GLenum type, GLuint id, GLenum severity,
                                      GLsizei length, const GLchar *message, const void *user)
{
    if (severity == GL_DEBUG_SEVERITY_NOTIFICATION)
        return;
    if (type == GL_DEBUG_TYPE_ERROR)
        log_warn("GL: %.*s", (int)length, message);
    else
        log_debug("GL: %.*s", (int)length, message);
}

bool gpu_context_setup_current(struct gpu_context *ctx, bool debug)
{
    int version = epoxy_gl_version();
    if (version < 45) {
        log_error("OpenGL 4.5 core is needed; this context has %d.%d (%s)", version / 10,
                  version % 10, (const char *)glGetString(GL_RENDERER));
        return false;
    }
    if (debug) {
        glEnable(GL_DEBUG_OUTPUT);
        glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
        glDebugMessageCallback(debug_callback, ctx);
    }
    log_debug("OpenGL %s on %s", (const char *)glGetString(GL_VERSION),
              (const char *)glGetString(GL_RENDERER));
    return true;
}

const char *gpu_renderer_name(void)
{
    static char name[256];
    snprintf(name, sizeof(name), "%s (OpenGL %s)", (const char *)glGetString(GL_RENDERER),
             (const char *)glGetString(GL_VERSION));
    return name;
}

/* ---- outputs: pure choices, testable without monitors ---------------------------------- */

int gpu_output_by_name(const struct gpu_output *outputs, int n, const char *name)
{
    for (int i = 0; i < n; i++) {
        if (strcmp(outputs[i].name, name) == 0)
            return i;
    }
    for (int i = 0; i < n; i++) {
        if (strcasecmp(outputs[i].name, name) == 0)
            return i;
    }
    return -1;
}

int gpu_output_by_rect(const struct gpu_output *outputs, int n, const int rect[4])
{
    for (int i = 0; i < n; i++) {
        if (memcmp(outputs[i].rect, rect, sizeof(outputs[i].rect)) == 0)
            return i;
    }
    return -1;
}

void gpu_output_list(const struct gpu_output *outputs, int n, char *out, size_t size)
{
    size_t len = 0;
    out[0] = '\0';
    for (int i = 0; i < n && len < size; i++)
        len += (size_t)snprintf(out + len, size - len, "%s%s at %d,%d %dx%d", i ? "; " : "",
                                outputs[i].name, outputs[i].rect[0], outputs[i].rect[1],
                                outputs[i].rect[2], outputs[i].rect[3]);
    if (n == 0)
        snprintf(out, size, "none");
}

int gpu_output_choose(const struct gpu_context_desc *desc, const struct gpu_output *outputs,
                      int n, bool *borderless)
{
    *borderless = false;
    char list[512];
    if (desc->output && desc->output[0]) {
        int i = gpu_output_by_name(outputs, n, desc->output);
        if (i >= 0)
            return i;
        gpu_output_list(outputs, n, list, sizeof(list));
        log_warn("%s: output \"%s\" is not connected (outputs: %s): opening a window instead",
                 desc->title ? desc->title : "window", desc->output, list);
        return -1;
    }
    if (desc->rect_set) {
        int i = gpu_output_by_rect(outputs, n, desc->rect);
        if (i >= 0)
            return i;
        gpu_output_list(outputs, n, list, sizeof(list));
        log_info("%s: no output is exactly at %d,%d %dx%d (outputs: %s): a borderless window "
                 "there", desc->title ? desc->title : "window", desc->rect[0], desc->rect[1],
                 desc->rect[2], desc->rect[3], list);
        *borderless = true;
        return -1;
    }
    if (desc->monitor >= 0 && desc->monitor < n)
        return desc->monitor;
    if (desc->monitor >= 0)
        log_warn("monitor %d does not exist (%d connected): opening a window instead",
                 desc->monitor, n);
    return -1;
}
