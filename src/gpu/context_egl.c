/* Headless contexts through EGL: Mesa's surfaceless platform first (llvmpipe, any Mesa
 * driver), then the EGL device platform (NVIDIA's driver), then the default display. */
#include <stdlib.h>
#include <string.h>

#include <epoxy/egl.h>

#include "common/log.h"
#include "gpu/context_impl.h"

struct egl_context {
    struct gpu_context base;
    EGLDisplay display;
    EGLConfig config; /* NULL (EGL_NO_CONFIG_KHR) when made without one */
    EGLContext context;
};

static bool has_extension(const char *list, const char *name)
{
    if (!list)
        return false;
    size_t len = strlen(name);
    for (const char *p = list; (p = strstr(p, name)); p += len) {
        if ((p == list || p[-1] == ' ') && (p[len] == ' ' || p[len] == '\0'))
            return true;
    }
    return false;
}

static EGLDisplay try_initialize(EGLDisplay dpy)
{
    if (dpy == EGL_NO_DISPLAY)
        return EGL_NO_DISPLAY;
    EGLint major, minor;
    if (!eglInitialize(dpy, &major, &minor))
        return EGL_NO_DISPLAY;
    return dpy;
}

/* Device INDEX (modulo the count) of the EGL device platform, or EGL_NO_DISPLAY. */
static EGLDisplay device_display(const char *client, int index)
{
    if (!has_extension(client, "EGL_EXT_platform_device"))
        return EGL_NO_DISPLAY;
    EGLDeviceEXT devices[16];
    EGLint count = 0;
    if (!eglQueryDevicesEXT(16, devices, &count) || count < 1)
        return EGL_NO_DISPLAY;
    int pick = index % count;
    EGLDisplay dpy =
        try_initialize(eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[pick], NULL));
    if (dpy != EGL_NO_DISPLAY)
        log_info("EGL: device %d of %d", pick, (int)count);
    return dpy;
}

static EGLDisplay open_display(int device)
{
    const char *client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    EGLDisplay dpy = EGL_NO_DISPLAY;
    if (device > 0) {
        dpy = device_display(client, device);
        if (dpy == EGL_NO_DISPLAY)
            log_warn("EGL: no device %d to choose (EGL_EXT_device_enumeration): the first one",
                     device);
        else
            return dpy;
    }
    if (has_extension(client, "EGL_MESA_platform_surfaceless"))
        dpy = try_initialize(eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA,
                                                      EGL_DEFAULT_DISPLAY, NULL));
    if (dpy == EGL_NO_DISPLAY && has_extension(client, "EGL_EXT_platform_device")) {
        EGLDeviceEXT devices[8];
        EGLint count = 0;
        if (eglQueryDevicesEXT(8, devices, &count)) {
            for (EGLint i = 0; i < count && dpy == EGL_NO_DISPLAY; i++)
                dpy = try_initialize(
                    eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[i], NULL));
        }
    }
    if (dpy == EGL_NO_DISPLAY)
        dpy = try_initialize(eglGetDisplay(EGL_DEFAULT_DISPLAY));
    return dpy;
}

static struct gpu_context *egl_create(const struct gpu_context_desc *desc)
{
    struct egl_context *c = calloc(1, sizeof(*c));
    if (!c)
        return NULL;
    c->base.width = desc->width;
    c->base.height = desc->height;
    c->display = open_display(desc->device);
    if (c->display == EGL_NO_DISPLAY) {
        log_error("no EGL display could be opened (no GPU driver or Mesa?)");
        goto error_alloc;
    }
    if (!eglBindAPI(EGL_OPENGL_API)) {
        log_error("EGL cannot bind the desktop OpenGL API");
        goto error_display;
    }
    const char *ext = eglQueryString(c->display, EGL_EXTENSIONS);
    EGLConfig config = NULL;
    if (desc->egl_config || !has_extension(ext, "EGL_KHR_no_config_context")) {
        /* A context shared with a runtime needs no surface of its own either. */
        const EGLint attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE,
                                  desc->egl_config ? 0 : EGL_WINDOW_BIT, EGL_NONE};
        EGLint n = 0;
        if (!eglChooseConfig(c->display, attribs, &config, 1, &n) || n < 1) {
            log_error("EGL has no OpenGL config");
            goto error_display;
        }
    }
    EGLint ctx_attribs[] = {
        EGL_CONTEXT_MAJOR_VERSION, 4,
        EGL_CONTEXT_MINOR_VERSION, 5,
        EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
        EGL_CONTEXT_OPENGL_DEBUG, desc->no_debug ? EGL_FALSE : EGL_TRUE,
        EGL_NONE,
    };
    c->config = config;
    c->context = eglCreateContext(c->display, config, EGL_NO_CONTEXT, ctx_attribs);
    if (c->context == EGL_NO_CONTEXT) {
        log_error("EGL could not create an OpenGL 4.5 core context (error 0x%x)",
                  eglGetError());
        goto error_display;
    }
    if (!eglMakeCurrent(c->display, EGL_NO_SURFACE, EGL_NO_SURFACE, c->context)) {
        log_error("EGL could not make the context current without a surface");
        goto error_context;
    }
    return &c->base;

error_context:
    eglDestroyContext(c->display, c->context);
error_display:
    eglTerminate(c->display);
error_alloc:
    free(c);
    return NULL;
}

static void egl_destroy(struct gpu_context *ctx)
{
    struct egl_context *c = (struct egl_context *)ctx;
    eglMakeCurrent(c->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(c->display, c->context);
    eglTerminate(c->display);
    free(c);
}

static void egl_make_current(struct gpu_context *ctx)
{
    struct egl_context *c = (struct egl_context *)ctx;
    eglMakeCurrent(c->display, EGL_NO_SURFACE, EGL_NO_SURFACE, c->context);
}

static bool egl_native(struct gpu_context *ctx, struct gpu_context_native *out)
{
    struct egl_context *c = (struct egl_context *)ctx;
    *out = (struct gpu_context_native){.kind = GPU_NATIVE_EGL, .display = c->display,
                                       .config = c->config, .context = c->context};
    return true;
}

const struct gpu_context_impl gpu_context_egl_impl = {
    .name = "egl",
    .description = "headless OpenGL 4.5 through EGL (Mesa surfaceless, EGL device, default)",
    .create = egl_create,
    .destroy = egl_destroy,
    .make_current = egl_make_current,
    .native = egl_native,
};
