/*
 * gpu internal: the context backend table.  Each backend embeds struct gpu_context as its
 * first member and fills a const gpu_context_impl; an entry a backend has no use for is NULL
 * (egl: no window, no swaps), and gpu_context_* then does what the public header says for
 * headless contexts.
 */
#ifndef ANVIL_GPU_CONTEXT_IMPL_H
#define ANVIL_GPU_CONTEXT_IMPL_H

#include "gpu/gpu.h"

/* What a runtime sharing a context needs of it (OpenXR's graphics bindings, context_xr.c). */
struct gpu_context_native {
    enum gpu_native_kind { GPU_NATIVE_NONE, GPU_NATIVE_EGL, GPU_NATIVE_X11_GLX } kind;
    void *display;        /* EGLDisplay; the X Display */
    void *config;         /* EGLConfig (EGL_NO_CONFIG_KHR when the context was made without) */
    void *context;        /* EGLContext; the GLXContext */
    unsigned long window; /* glx: the window's GLX drawable */
};

struct gpu_context_impl {
    const char *name;
    const char *description;
    struct gpu_context *(*create)(const struct gpu_context_desc *desc);
    void (*destroy)(struct gpu_context *ctx);
    void (*make_current)(struct gpu_context *ctx);
    void (*swap)(struct gpu_context *ctx);
    /* Vertical blanks a swap waits for; called with CTX current. */
    void (*swap_interval)(struct gpu_context *ctx, int interval);
    void (*size)(struct gpu_context *ctx, int *w, int *h);
    void *(*window)(struct gpu_context *ctx);
    /* The native handles (NULL: none to share). */
    bool (*native)(struct gpu_context *ctx, struct gpu_context_native *out);
    /* Joins swap group GROUP bound to barrier BARRIER (GLX_NV_swap_group); CTX current. */
    bool (*join_swap_group)(struct gpu_context *ctx, unsigned group, unsigned barrier);
};

struct gpu_context {
    const struct gpu_context_impl *impl;
    bool stereo;
    int width, height;
};

extern const struct gpu_context_impl gpu_context_egl_impl;
extern const struct gpu_context_impl gpu_context_glfw_impl;

/* Shared set-up once a context is current: checks the version, hooks the debug output. */
bool gpu_context_setup_current(struct gpu_context *ctx, bool debug);

#endif
