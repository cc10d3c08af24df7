/* Window contexts through GLFW. */
#include <stdio.h>
#include <stdlib.h>

#include <epoxy/gl.h>
#include <epoxy/glx.h> /* before glfw3native.h, which would include GL/glx.h */
#include <GLFW/glfw3.h>
#define GLFW_EXPOSE_NATIVE_X11
#define GLFW_EXPOSE_NATIVE_GLX
#include <GLFW/glfw3native.h>

#include "common/log.h"
#include "gpu/context_impl.h"

struct glfw_context {
    struct gpu_context base;
    GLFWwindow *window;
};

static int glfw_users;

static void error_callback(int code, const char *text)
{
    log_warn("GLFW: %s (0x%x)", text, code);
}

static struct gpu_context *glfw_create(const struct gpu_context_desc *desc)
{
    if (glfw_users == 0) {
        glfwSetErrorCallback(error_callback);
        if (!glfwInit()) {
            log_error("GLFW could not start (no window system? use the headless \"egl\" "
                      "backend, e.g. anvil render, or run under xvfb-run)");
            return NULL;
        }
    }
    glfw_users++;
    struct glfw_context *c = calloc(1, sizeof(*c));
    if (!c)
        goto error_glfw;
    glfwDefaultWindowHints();
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_OPENGL_DEBUG_CONTEXT, desc->no_debug ? GLFW_FALSE : GLFW_TRUE);
    glfwWindowHint(GLFW_AUTO_ICONIFY, GLFW_FALSE);
    glfwWindowHint(GLFW_STEREO, desc->stereo ? GLFW_TRUE : GLFW_FALSE);
    GLFWmonitor *monitor = NULL;
    bool borderless = false;
    if (desc->monitor >= 0 || desc->rect_set || (desc->output && desc->output[0])) {
        int count = 0;
        GLFWmonitor **monitors = glfwGetMonitors(&count);
        struct gpu_output outputs[16];
        int n = count < 16 ? count : 16;
        for (int i = 0; i < n; i++) {
            const char *name = glfwGetMonitorName(monitors[i]);
            snprintf(outputs[i].name, sizeof(outputs[i].name), "%s", name ? name : "?");
            glfwGetMonitorPos(monitors[i], &outputs[i].rect[0], &outputs[i].rect[1]);
            const GLFWvidmode *mode = glfwGetVideoMode(monitors[i]);
            outputs[i].rect[2] = mode ? mode->width : 0;
            outputs[i].rect[3] = mode ? mode->height : 0;
        }
        int chosen = gpu_output_choose(desc, outputs, n, &borderless);
        if (chosen >= 0)
            monitor = monitors[chosen];
    }
    int w = desc->width > 0 ? desc->width : 960, h = desc->height > 0 ? desc->height : 720;
    if (borderless) {
        w = desc->rect[2];
        h = desc->rect[3];
        glfwWindowHint(GLFW_DECORATED, GLFW_FALSE);
        glfwWindowHint(GLFW_FLOATING, GLFW_TRUE);
    }
    c->window = glfwCreateWindow(w, h, desc->title ? desc->title : "anvil", monitor,
                                 (GLFWwindow *)desc->share_window);
    if (!c->window && desc->stereo) {
        log_warn("no quad-buffer stereo framebuffer on this driver: falling back to mono");
        glfwWindowHint(GLFW_STEREO, GLFW_FALSE);
        c->window = glfwCreateWindow(w, h, desc->title ? desc->title : "anvil", monitor,
                                     (GLFWwindow *)desc->share_window);
    } else if (c->window) {
        c->base.stereo = desc->stereo;
    }
    if (!c->window) {
        log_error("GLFW could not open an OpenGL 4.5 core window");
        goto error_alloc;
    }
    if (borderless)
        glfwSetWindowPos(c->window, desc->rect[0], desc->rect[1]);
    glfwMakeContextCurrent(c->window);
    glfwSwapInterval(1);
    c->base.width = w;
    c->base.height = h;
    return &c->base;

error_alloc:
    free(c);
error_glfw:
    if (--glfw_users == 0)
        glfwTerminate();
    return NULL;
}

static void glfw_destroy(struct gpu_context *ctx)
{
    struct glfw_context *c = (struct glfw_context *)ctx;
    glfwDestroyWindow(c->window);
    free(c);
    if (--glfw_users == 0)
        glfwTerminate();
}

static void glfw_make_current(struct gpu_context *ctx)
{
    glfwMakeContextCurrent(((struct glfw_context *)ctx)->window);
}

static void glfw_swap(struct gpu_context *ctx)
{
    glfwSwapBuffers(((struct glfw_context *)ctx)->window);
}

static void glfw_swap_interval(struct gpu_context *ctx, int interval)
{
    glfwSwapInterval(interval); /* applies to the current context: CTX */
}

static void glfw_size(struct gpu_context *ctx, int *w, int *h)
{
    glfwGetFramebufferSize(((struct glfw_context *)ctx)->window, w, h);
}

static void *glfw_window(struct gpu_context *ctx)
{
    return ((struct glfw_context *)ctx)->window;
}

static bool glfw_native(struct gpu_context *ctx, struct gpu_context_native *out)
{
    struct glfw_context *c = (struct glfw_context *)ctx;
    Display *dpy = glfwGetX11Display();
    GLXContext glx = glfwGetGLXContext(c->window);
    if (!dpy || !glx) /* not X11 with GLX (Wayland, or a context made through EGL) */
        return false;
    *out = (struct gpu_context_native){.kind = GPU_NATIVE_X11_GLX, .display = dpy,
                                       .context = glx,
                                       .window = (unsigned long)glfwGetGLXWindow(c->window)};
    return true;
}

/* GLX_NV_swap_group (NVIDIA Quadro and its framelock boards): the windows of every rank swap
 * together when they are in one group bound to one barrier. */
static bool glfw_join_swap_group(struct gpu_context *ctx, unsigned group, unsigned barrier)
{
    struct glfw_context *c = (struct glfw_context *)ctx;
    Display *dpy = glfwGetX11Display();
    if (!dpy || !glfwGetGLXContext(c->window) ||
        !epoxy_has_glx_extension(dpy, DefaultScreen(dpy), "GLX_NV_swap_group"))
        return false;
    GLuint max_groups = 0, max_barriers = 0;
    if (!glXQueryMaxSwapGroupsNV(dpy, DefaultScreen(dpy), &max_groups, &max_barriers) ||
        group > max_groups || barrier > max_barriers)
        return false;
    if (!glXJoinSwapGroupNV(dpy, glfwGetGLXWindow(c->window), group))
        return false;
    return barrier == 0 || glXBindSwapBarrierNV(dpy, group, barrier);
}

const struct gpu_context_impl gpu_context_glfw_impl = {
    .name = "glfw",
    .description = "OpenGL 4.5 core window through GLFW (X11/Wayland; quad-buffer stereo "
                   "where the driver has it)",
    .create = glfw_create,
    .destroy = glfw_destroy,
    .make_current = glfw_make_current,
    .swap = glfw_swap,
    .swap_interval = glfw_swap_interval,
    .size = glfw_size,
    .window = glfw_window,
    .native = glfw_native,
    .join_swap_group = glfw_join_swap_group,
};
