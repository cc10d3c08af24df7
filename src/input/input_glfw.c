/* The desktop wand: GLFW keyboard, mouse (the ray through the pointer) and joystick. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <GLFW/glfw3.h>

#include "common/log.h"
#include "input/input_impl.h"

#define WINDOWS_MAX 8

struct glfw_input {
    struct input_source base;
    GLFWwindow *window;
    GLFWkeyfun prev_key;
    GLFWmousebuttonfun prev_button;
    struct input_queue pending; /* from callbacks, handed out at the next poll */
    double cursor[2];
    bool capture;
    bool left_captured; /* the last left press went to the wand: so does its release */
    unsigned char joy_buttons[INPUT_BUTTON_COUNT];
    float joy_axes[INPUT_AXIS_COUNT];
};

/* GLFW callbacks get only the window; its user pointer belongs to others. */
static struct glfw_input *registry[WINDOWS_MAX];

static struct glfw_input *find(GLFWwindow *w)
{
    for (int i = 0; i < WINDOWS_MAX; i++)
        if (registry[i] && registry[i]->window == w)
            return registry[i];
    return NULL;
}

static void push_button(struct glfw_input *g, enum input_button b, bool down)
{
    struct input_event e = {.type = INPUT_BUTTON, .button = b, .down = down};
    input_queue_push(&g->pending, &e);
}

static void on_key(GLFWwindow *w, int key, int scancode, int action, int mods)
{
    struct glfw_input *g = find(w);
    if (!g)
        return;
    if (action == GLFW_PRESS) {
        enum input_key k = INPUT_KEY_NONE;
        switch (key) {
        case GLFW_KEY_SPACE:
            k = INPUT_KEY_PLAY;
            break;
        case GLFW_KEY_COMMA:
            k = INPUT_KEY_STEP_BACK;
            break;
        case GLFW_KEY_PERIOD:
            k = INPUT_KEY_STEP_FORWARD;
            break;
        case GLFW_KEY_TAB:
        case GLFW_KEY_M:
            k = INPUT_KEY_MENU;
            break;
        case GLFW_KEY_RIGHT_BRACKET:
            k = INPUT_KEY_PAGE_NEXT;
            break;
        case GLFW_KEY_LEFT_BRACKET:
            k = INPUT_KEY_PAGE_PREV;
            break;
        case GLFW_KEY_HOME:
            push_button(g, INPUT_BUTTON_RESET, true);
            push_button(g, INPUT_BUTTON_RESET, false);
            break;
        default:
            break;
        }
        if (k != INPUT_KEY_NONE) {
            struct input_event e = {.type = INPUT_KEY, .key = k};
            input_queue_push(&g->pending, &e);
        }
    }
    if (g->prev_key)
        g->prev_key(w, key, scancode, action, mods);
}

static void on_button(GLFWwindow *w, int button, int action, int mods)
{
    struct glfw_input *g = find(w);
    if (!g)
        return;
    bool down = action == GLFW_PRESS;
    bool chain = true;
    if (button == GLFW_MOUSE_BUTTON_LEFT) {
        push_button(g, INPUT_BUTTON_TRIGGER, down);
        if (down)
            g->left_captured = g->capture;
        chain = !g->left_captured;
        if (!down)
            g->left_captured = false;
    } else if (button == GLFW_MOUSE_BUTTON_MIDDLE) {
        push_button(g, INPUT_BUTTON_GRAB, down);
    } else if (button == GLFW_MOUSE_BUTTON_RIGHT && down) {
        struct input_event e = {.type = INPUT_KEY, .key = INPUT_KEY_MENU};
        input_queue_push(&g->pending, &e);
    }
    if (chain && g->prev_button)
        g->prev_button(w, button, action, mods);
}

static void unproject(const float m[16], float x, float y, float z, float out[3])
{
    float v[4];
    for (int r = 0; r < 4; r++)
        v[r] = m[r] * x + m[4 + r] * y + m[8 + r] * z + m[12 + r];
    for (int i = 0; i < 3; i++)
        out[i] = v[i] / v[3];
}

static void poll_joystick(struct glfw_input *g, struct input_queue *q)
{
    if (!glfwJoystickPresent(GLFW_JOYSTICK_1))
        return;
    int nb = 0, na = 0;
    const unsigned char *buttons = glfwGetJoystickButtons(GLFW_JOYSTICK_1, &nb);
    const float *axes = glfwGetJoystickAxes(GLFW_JOYSTICK_1, &na);
    for (int b = 0; b < INPUT_BUTTON_COUNT && b < nb; b++) {
        if (buttons[b] != g->joy_buttons[b]) {
            g->joy_buttons[b] = buttons[b];
            struct input_event e = {.type = INPUT_BUTTON, .button = (enum input_button)b,
                                    .down = buttons[b] == GLFW_PRESS};
            input_queue_push(q, &e);
        }
    }
    /* Left stick: up flies forward, sideways turns. */
    float want[INPUT_AXIS_COUNT] = {na > 1 ? -axes[1] : 0.0f, na > 0 ? axes[0] : 0.0f};
    for (int a = 0; a < INPUT_AXIS_COUNT; a++) {
        float v = fabsf(want[a]) < 0.15f ? 0.0f : want[a]; /* dead zone */
        if (v != g->joy_axes[a]) {
            g->joy_axes[a] = v;
            struct input_event e = {.type = INPUT_AXIS, .axis = (enum input_axis)a, .value = v};
            input_queue_push(q, &e);
        }
    }
}

static bool glfw_poll(struct input_source *s, const struct input_frame *frame,
                      struct input_queue *q)
{
    struct glfw_input *g = (struct glfw_input *)s;
    if (frame->have_camera && frame->width > 0 && frame->height > 0) {
        int ww, wh;
        glfwGetWindowSize(g->window, &ww, &wh);
        glfwGetCursorPos(g->window, &g->cursor[0], &g->cursor[1]);
        if (ww > 0 && wh > 0) {
            float x = (float)((g->cursor[0] + 0.5) / ww * 2.0 - 1.0);
            float y = (float)(1.0 - (g->cursor[1] + 0.5) / wh * 2.0);
            struct input_event e = {.type = INPUT_POSE, .space = INPUT_SPACE_WORLD};
            float far[3];
            unproject(frame->inv_view_proj, x, y, -1.0f, e.position);
            unproject(frame->inv_view_proj, x, y, 1.0f, far);
            float len = 0.0f;
            for (int i = 0; i < 3; i++) {
                e.direction[i] = far[i] - e.position[i];
                len += e.direction[i] * e.direction[i];
            }
            len = sqrtf(len);
            if (len > 0.0f && isfinite(len)) {
                for (int i = 0; i < 3; i++)
                    e.direction[i] /= len;
                input_queue_push(q, &e);
            }
        }
    }
    /* The pose first, then what the callbacks saw, so a click acts where the pointer is. */
    for (int i = 0; i < g->pending.count; i++)
        input_queue_push(q, &g->pending.events[i]);
    input_queue_clear(&g->pending);
    poll_joystick(g, q);
    return true;
}

static void glfw_destroy(struct input_source *s)
{
    struct glfw_input *g = (struct glfw_input *)s;
    for (int i = 0; i < WINDOWS_MAX; i++)
        if (registry[i] == g)
            registry[i] = NULL;
    glfwSetKeyCallback(g->window, g->prev_key);
    glfwSetMouseButtonCallback(g->window, g->prev_button);
    free(g);
}

static const struct input_source_impl glfw_impl = {
    .name = "glfw",
    .poll = glfw_poll,
    .destroy = glfw_destroy,
};

struct input_source *input_glfw_create(void *window)
{
    int slot = -1;
    for (int i = 0; i < WINDOWS_MAX && slot < 0; i++)
        if (!registry[i])
            slot = i;
    if (!window || slot < 0) {
        log_error("desktop input: no window, or too many windows");
        return NULL;
    }
    struct glfw_input *g = calloc(1, sizeof(*g));
    if (!g) {
        log_error("desktop input: out of memory");
        return NULL;
    }
    g->base.impl = &glfw_impl;
    g->window = window;
    registry[slot] = g;
    g->prev_key = glfwSetKeyCallback(window, on_key);
    g->prev_button = glfwSetMouseButtonCallback(window, on_button);
    return &g->base;
}

void input_glfw_capture(struct input_source *s, bool capture)
{
    if (s && s->impl == &glfw_impl)
        ((struct glfw_input *)s)->capture = capture;
}
