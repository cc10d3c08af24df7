/* Swap intervals of window contexts: several windows (CAVE walls) swap together. */
#include <string.h>

#include <GLFW/glfw3.h>

#include "gpu/context_impl.h"

void gpu_context_swap_interval(struct gpu_context *ctx, int interval)
{
    if (!ctx || strcmp(ctx->impl->name, "glfw") != 0)
        return;
    gpu_context_make_current(ctx);
    glfwSwapInterval(interval);
}
