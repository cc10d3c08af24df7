/* input internal: the source vtable; each backend embeds struct input_source first. */
#ifndef ANVIL_INPUT_IMPL_H
#define ANVIL_INPUT_IMPL_H

#include "input/input.h"

struct input_source_impl {
    const char *name;
    bool (*poll)(struct input_source *s, const struct input_frame *frame,
                 struct input_queue *q);
    bool (*finished)(const struct input_source *s); /* NULL: never */
    void (*destroy)(struct input_source *s);
};

struct input_source {
    const struct input_source_impl *impl;
};

#endif
