/*
 * display internal: the backend table.  Each backend embeds struct display as its first member
 * and fills a const display_impl; display.c does what every backend shares (the head, the view
 * set, the frame loop, files).
 */
#ifndef ANVIL_DISPLAY_IMPL_H
#define ANVIL_DISPLAY_IMPL_H

#include <openhmd.h>

#include "display/display.h"

#define DISPLAY_MAX_OUTPUTS 4

struct display;

struct display_impl {
    const char *name;
    const char *description;
    /* Allocates the backend's struct (base first) and opens its windows or devices; the
     * primary context must be current on return.  BASE holds the copied config and desc. */
    struct display *(*create)(const struct display *base);
    void (*destroy)(struct display *d);
    /* Fills d->views for head pose HEAD (NULL: the backend's default layout). */
    bool (*layout)(struct display *d, const struct display_pose *head);
    /* Composes and shows the drawn views. */
    bool (*present)(struct display *d, struct renderer *r, float exposure);
};

struct display_output {
    char name[48];
    struct gpu_texture hdr; /* linear RGBA32F */
};

/* Head pose sources behind one struct. */
struct display_head_tracker {
    enum display_head_source source;
    struct display_pose fixed;   /* fixed; also the offset added to a device's position */
    struct display_path path;
    ohmd_context *ohmd;
    ohmd_device *device;
};

struct display {
    const struct display_impl *impl;
    struct display_config cfg;
    struct display_desc desc;
    struct gpu_context *context; /* primary */
    bool own_context;
    struct display_head_tracker head;
    struct view_set set;
    struct display_output outputs[DISPLAY_MAX_OUTPUTS];
    int output_count;
    struct gpu_program compose; /* shaders/display_compose.comp */
    bool should_close;
    bool nav_changed;
    double time;
};

extern const struct display_impl display_headless_impl;
extern const struct display_impl display_desktop_impl;
extern const struct display_impl display_stereo_impl;
extern const struct display_impl display_cave_impl;
extern const struct display_impl display_hmd_impl;

/* Shared by backends. */

/* The walls' image sizes offscreen (config size or desc height and aspect). */
void display_offscreen_sizes(const struct display *d, int (*sizes)[2]);

/* Makes output I named NAME hold a W x H RGBA32F texture. */
struct display_output *display_output_ensure(struct display *d, int i, const char *name, int w,
                                             int h);

/* Composes two eye images into OUT at pixel (X, Y): MODE 0 copy LEFT only, 1 anaglyph
 * (red = left luminance, green and blue = right). */
bool display_compose(struct display *d, const struct gpu_texture *left,
                     const struct gpu_texture *right, int mode, struct gpu_texture *out, int x,
                     int y);

/* Tone maps IN and blits it into the current window's back buffer region. */
bool display_show(struct renderer *r, const struct gpu_texture *in, float exposure,
                  struct gpu_texture *scratch, int x, int y, int w, int h, int buffer);

/* Makes the primary context: offscreen, the desc's context or a new EGL one; else a GLFW
 * window W x H (fullscreen on MONITOR >= 0) with quad-buffer STEREO asked for. */
bool display_open_primary(struct display *d, int w, int h, int monitor, bool stereo,
                          const char *title);
/* Closes the primary context if the display made it. */
void display_close_primary(struct display *d);

/* Sets up keyboard flying and close on Esc/Q for WINDOW (a GLFWwindow). */
void display_watch_window(struct display *d, void *window);

/* OpenHMD: opens the device named NAME ("null": the Null HMD; else a product name, matched
 * case-insensitively as a substring) of class CLASS (OHMD_DEVICE_CLASS_*), or -1 for any
 * class.  Returns false (logged with the devices found) when none matches. */
bool display_ohmd_open(const char *name, int device_class, ohmd_context **ctx,
                       ohmd_device **device);

/* Head trackers. */
bool display_head_tracker_init(struct display_head_tracker *h, const struct display_head *cfg);
void display_head_tracker_finish(struct display_head_tracker *h);
bool display_head_tracker_pose(struct display_head_tracker *h, double t,
                               struct display_pose *out);

#endif
