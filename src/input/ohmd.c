/*
 * OpenHMD: one context per process, shared by everything that reads a device (the HMD's
 * panel and lenses, a head tracker, the wand), and devices opened by name (never by index:
 * indices change with what is plugged in).  A device opened twice is the same device, counted.
 */
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include <openhmd.h>

#include "common/log.h"
#include "input/input.h"

#define OPEN_MAX 8

static ohmd_context *context;
static int context_users;
static struct {
    ohmd_device *device;
    int index, users;
} open_devices[OPEN_MAX];

static bool name_matches(const char *product, const char *want)
{
    size_t n = strlen(want);
    for (const char *p = product; *p; p++) {
        if (strncasecmp(p, want, n) == 0)
            return true;
    }
    return n == 0;
}

static const char *class_name(int device_class)
{
    return device_class == OHMD_DEVICE_CLASS_HMD          ? "HMD"
           : device_class == OHMD_DEVICE_CLASS_CONTROLLER ? "controller"
                                                          : "device";
}

static void release_context(void)
{
    if (--context_users == 0) {
        ohmd_ctx_destroy(context); /* closes its devices */
        context = NULL;
    }
}

struct ohmd_device *input_ohmd_open(const char *name, int device_class)
{
    if (!context) {
        context = ohmd_ctx_create();
        if (!context) {
            log_error("OpenHMD: could not create a context");
            return NULL;
        }
    }
    context_users++;
    int count = ohmd_ctx_probe(context);
    bool want_null = strcasecmp(name, "null") == 0;
    int found = -1;
    for (int i = 0; i < count && found < 0; i++) {
        int flags = 0, cls = -1;
        ohmd_list_geti(context, i, OHMD_DEVICE_FLAGS, &flags);
        ohmd_list_geti(context, i, OHMD_DEVICE_CLASS, &cls);
        if (device_class >= 0 && cls != device_class)
            continue;
        const char *product = ohmd_list_gets(context, i, OHMD_PRODUCT);
        if (want_null ? (flags & OHMD_DEVICE_FLAGS_NULL_DEVICE) != 0
                      : name_matches(product ? product : "", name))
            found = i;
    }
    if (found < 0) {
        char list[512] = "";
        size_t len = 0;
        for (int i = 0; i < count && len < sizeof(list); i++) {
            const char *product = ohmd_list_gets(context, i, OHMD_PRODUCT);
            len += (size_t)snprintf(list + len, sizeof(list) - len, "%s\"%s\"", i ? ", " : "",
                                    product ? product : "?");
        }
        log_error("OpenHMD: no %s named \"%s\" (found: %s; \"null\" picks the Null %s)",
                  class_name(device_class), name, count > 0 ? list : "none",
                  class_name(device_class));
        release_context();
        return NULL;
    }
    for (int i = 0; i < OPEN_MAX; i++) {
        if (open_devices[i].device && open_devices[i].index == found) {
            open_devices[i].users++;
            return open_devices[i].device;
        }
    }
    int slot = -1;
    for (int i = 0; i < OPEN_MAX && slot < 0; i++)
        if (!open_devices[i].device)
            slot = i;
    ohmd_device *dev = slot >= 0 ? ohmd_list_open_device(context, found) : NULL;
    if (!dev) {
        log_error("OpenHMD: could not open \"%s\": %s",
                  ohmd_list_gets(context, found, OHMD_PRODUCT),
                  slot < 0 ? "too many open devices" : ohmd_ctx_get_error(context));
        release_context();
        return NULL;
    }
    open_devices[slot].device = dev;
    open_devices[slot].index = found;
    open_devices[slot].users = 1;
    log_info("OpenHMD: opened \"%s\"", ohmd_list_gets(context, found, OHMD_PRODUCT));
    return dev;
}

void input_ohmd_close(struct ohmd_device *dev)
{
    if (!dev)
        return;
    for (int i = 0; i < OPEN_MAX; i++) {
        if (open_devices[i].device != dev)
            continue;
        if (--open_devices[i].users == 0) {
            ohmd_close_device(dev);
            open_devices[i].device = NULL;
        }
        release_context();
        return;
    }
}

void input_ohmd_update(void)
{
    if (context)
        ohmd_ctx_update(context);
}

const char *input_ohmd_product(const struct ohmd_device *dev)
{
    for (int i = 0; i < OPEN_MAX && context; i++)
        if (open_devices[i].device == dev)
            return ohmd_list_gets(context, open_devices[i].index, OHMD_PRODUCT);
    return "?";
}

int input_ohmd_contexts(void)
{
    return context ? 1 : 0;
}
