/* OpenHMD controllers as the wand: pose (tracker space) and controls as buttons. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <openhmd.h>

#include "common/log.h"
#include "input/input_impl.h"

#define CONTROLS_MAX 64

struct ohmd_input {
    struct input_source base;
    ohmd_device *device; /* shared (input_ohmd_open) */
    double offset[3];
    int control_count;
    int hints[CONTROLS_MAX];
    bool pressed[CONTROLS_MAX];
    bool primed; /* PRESSED holds the controls' state of a first poll */
    float last_pose[9];
};

/* The wand button an OpenHMD control hint stands for, or -1. */
static int button_of(int hint)
{
    switch (hint) {
    case OHMD_TRIGGER:
    case OHMD_TRIGGER_CLICK:
    case OHMD_BUTTON_A:
        return INPUT_BUTTON_TRIGGER;
    case OHMD_SQUEEZE:
    case OHMD_BUTTON_B:
        return INPUT_BUTTON_GRAB;
    case OHMD_MENU:
    case OHMD_BUTTON_X:
        return INPUT_BUTTON_MENU;
    case OHMD_HOME:
    case OHMD_BUTTON_Y:
        return INPUT_BUTTON_RESET;
    default:
        return -1;
    }
}

/* Rotates (0, 0, -1) (OpenHMD's forward) by the quaternion Q (x, y, z, w). */
static void forward_of(const float q[4], float out[3])
{
    float x = q[0], y = q[1], z = q[2], w = q[3];
    out[0] = -(2.0f * (x * z + w * y));
    out[1] = -(2.0f * (y * z - w * x));
    out[2] = -(1.0f - 2.0f * (x * x + y * y));
}

/* Rotates (0, 1, 0) (the controller's up) by the quaternion Q (x, y, z, w). */
static void up_of(const float q[4], float out[3])
{
    float x = q[0], y = q[1], z = q[2], w = q[3];
    out[0] = 2.0f * (x * y - w * z);
    out[1] = 1.0f - 2.0f * (x * x + z * z);
    out[2] = 2.0f * (y * z + w * x);
}

static bool ohmd_poll(struct input_source *s, const struct input_frame *frame,
                      struct input_queue *q)
{
    struct ohmd_input *h = (struct ohmd_input *)s;
    input_ohmd_update();
    float rot[4] = {0, 0, 0, 1}, pos[3] = {0, 0, 0};
    ohmd_device_getf(h->device, OHMD_ROTATION_QUAT, rot);
    ohmd_device_getf(h->device, OHMD_POSITION_VECTOR, pos);
    struct input_event e = {.type = INPUT_POSE, .space = INPUT_SPACE_TRACKER, .has_up = true};
    forward_of(rot, e.direction);
    up_of(rot, e.up);
    for (int i = 0; i < 3; i++)
        e.position[i] = pos[i] + (float)h->offset[i];
    float pose[9] = {e.position[0],  e.position[1],  e.position[2],
                     e.direction[0], e.direction[1], e.direction[2],
                     e.up[0],        e.up[1],        e.up[2]};
    if (memcmp(pose, h->last_pose, sizeof(pose)) != 0 || frame->frame == 0) {
        memcpy(h->last_pose, pose, sizeof(pose));
        input_queue_push(q, &e);
    }
    if (h->control_count > 0) {
        float state[CONTROLS_MAX] = {0};
        ohmd_device_getf(h->device, OHMD_CONTROLS_STATE, state);
        /* The first poll only learns the state: a control already held when the device
         * opened (OpenHMD's Null controller reports its menu control as held throughout) is
         * no press, and a press begins when a control changes. */
        bool first = !h->primed;
        h->primed = true;
        for (int c = 0; c < h->control_count; c++) {
            int b = button_of(h->hints[c]);
            bool down = state[c] > 0.5f;
            if (first) {
                h->pressed[c] = down;
                continue;
            }
            if (b < 0 || down == h->pressed[c])
                continue;
            h->pressed[c] = down;
            struct input_event be = {.type = INPUT_BUTTON, .button = (enum input_button)b,
                                     .down = down};
            input_queue_push(q, &be);
        }
    }
    return true;
}

static void ohmd_destroy(struct input_source *s)
{
    struct ohmd_input *h = (struct ohmd_input *)s;
    input_ohmd_close(h->device);
    free(h);
}

static const struct input_source_impl ohmd_impl = {
    .name = "openhmd",
    .poll = ohmd_poll,
    .destroy = ohmd_destroy,
};

struct input_source *input_ohmd_create(const char *name, const double offset[3])
{
    struct ohmd_input *h = calloc(1, sizeof(*h));
    if (!h) {
        log_error("OpenHMD controller: out of memory");
        return NULL;
    }
    h->base.impl = &ohmd_impl;
    for (int i = 0; i < 3 && offset; i++)
        h->offset[i] = offset[i];
    h->device = input_ohmd_open(name, OHMD_DEVICE_CLASS_CONTROLLER);
    if (!h->device)
        goto error;
    ohmd_device_geti(h->device, OHMD_CONTROL_COUNT, &h->control_count);
    if (h->control_count > CONTROLS_MAX)
        h->control_count = CONTROLS_MAX;
    if (h->control_count > 0) {
        int hints[256] = {0};
        ohmd_device_geti(h->device, OHMD_CONTROLS_HINTS, hints);
        memcpy(h->hints, hints, sizeof(int) * (size_t)h->control_count);
    }
    log_info("OpenHMD: wand \"%s\" (%d controls)", input_ohmd_product(h->device),
             h->control_count);
    return &h->base;

error:
    ohmd_destroy(&h->base);
    return NULL;
}
