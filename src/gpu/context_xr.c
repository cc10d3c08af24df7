/*
 * A context as an OpenXR runtime takes it (XR_KHR_opengl_enable): the graphics binding that
 * XrSessionCreateInfo chains, made from the context backend's native handles, and the one
 * swapchain format the display part writes.  Built only with the OpenXR loader (HAVE_OPENXR);
 * the only gpu code that includes OpenXR's platform header, which needs EGL's and GLX's types.
 */
#include <string.h>

#include <epoxy/egl.h>
#include <epoxy/gl.h>
#include <epoxy/glx.h>

#define XR_USE_GRAPHICS_API_OPENGL
#define XR_USE_PLATFORM_EGL
#define XR_USE_PLATFORM_XLIB
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>

#include "common/log.h"
#include "gpu/context_impl.h"

_Static_assert(sizeof(XrGraphicsBindingEGLMNDX) <= GPU_XR_BINDING_BYTES, "binding size");
_Static_assert(sizeof(XrGraphicsBindingOpenGLXlibKHR) <= GPU_XR_BINDING_BYTES, "binding size");

/* The GLX framebuffer config and X visual the context was made with. */
static bool glx_config(Display *dpy, GLXContext ctx, GLXFBConfig *config, uint32_t *visual)
{
    int id = 0, n = 0;
    if (glXQueryContext(dpy, ctx, GLX_FBCONFIG_ID, &id) != Success)
        return false;
    const int attribs[] = {GLX_FBCONFIG_ID, id, None};
    GLXFBConfig *configs = glXChooseFBConfig(dpy, DefaultScreen(dpy), attribs, &n);
    if (!configs || n < 1)
        return false;
    *config = configs[0];
    XFree(configs);
    XVisualInfo *vi = glXGetVisualFromFBConfig(dpy, *config);
    if (!vi)
        return false;
    *visual = (uint32_t)vi->visualid;
    XFree(vi);
    return true;
}

const char *gpu_context_xr_binding(struct gpu_context *ctx, void *binding)
{
    struct gpu_context_native n = {0};
    if (!ctx->impl->native || !ctx->impl->native(ctx, &n)) {
        log_error("OpenXR: the %s context has no handles a runtime can share (a GLX window "
                  "on X11 or a headless EGL context is needed)",
                  ctx->impl->name);
        return NULL;
    }
    memset(binding, 0, GPU_XR_BINDING_BYTES);
    if (n.kind == GPU_NATIVE_EGL) {
        XrGraphicsBindingEGLMNDX *b = binding;
        b->type = XR_TYPE_GRAPHICS_BINDING_EGL_MNDX;
        b->getProcAddress = (PFNEGLGETPROCADDRESSPROC)eglGetProcAddress;
        b->display = n.display;
        b->config = n.config;
        b->context = n.context;
        return XR_MNDX_EGL_ENABLE_EXTENSION_NAME;
    }
    XrGraphicsBindingOpenGLXlibKHR *b = binding;
    b->type = XR_TYPE_GRAPHICS_BINDING_OPENGL_XLIB_KHR;
    b->xDisplay = n.display;
    b->glxContext = n.context;
    b->glxDrawable = (GLXDrawable)n.window;
    if (!glx_config(n.display, n.context, &b->glxFBConfig, &b->visualid)) {
        log_error("OpenXR: the GLX framebuffer config of the window cannot be found");
        return NULL;
    }
    return "";
}

int64_t gpu_xr_swapchain_format(const int64_t *formats, int count)
{
    for (int i = 0; i < count; i++) {
        if (formats[i] == GL_SRGB8_ALPHA8)
            return formats[i];
    }
    return 0;
}
