#include <stdio.h>
#include <string.h>

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
