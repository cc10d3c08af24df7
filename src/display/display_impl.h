/*
 * display internal: the backend table.  Each backend embeds struct display as its first member
 * and fills a const display_impl; display.c does what every backend shares (the head, the view
 * set, the frame loop, files).
 */
#ifndef ANVIL_DISPLAY_IMPL_H
#define ANVIL_DISPLAY_IMPL_H

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
    /* Fills d->set for head pose HEAD, navigation NAV and orbit camera CAMERA. */
    bool (*layout)(struct display *d, const struct display_pose *head,
                   const struct display_navigation *nav, const struct display_camera *camera);
    /* Composes and shows the drawn views. */
    bool (*present)(struct display *d, struct renderer *r, float exposure);
    /* Optional, for a display with a head of its own (a runtime's headset): the head pose
     * at time T, in place of the head tracker's (NULL: the head tracker). */
    bool (*sample_head)(struct display *d, double t, struct display_pose *head);
    /* Optional, for a display whose runtime gives the eyes relative to the head every frame:
     * those the last layout drew (display_eyes_in_head), and the eyes to draw instead
     * (display_give_eyes, NULL: the runtime's). */
    bool (*eyes_in_head)(const struct display *d, struct display_pose out[2]);
    void (*give_eyes)(struct display *d, const struct display_pose eyes[2]);
    /* Optional: appends the display's own devices' events (a runtime's controllers, its
     * session ending) to Q, before the windows' events. */
    void (*poll_input)(struct display *d, double timeout_s, struct input_queue *q);
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
    struct ohmd_device *device; /* the process's OpenHMD context's (input_ohmd_open) */
    struct tracker *tracker;    /* dtrack, vrpn: the head's body (input/tracker.h) */
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
    double time;
    /* Window events since the last display_poll_input (callbacks push here). */
    struct input_queue pending;
    bool dragging;
    double cursor[2], drag_from[2];
    /* The desktop wand's last pose as pushed: the cursor, the window and the first view's
     * view-projection it came from (push_pointer pushes again only when one of them moves). */
    bool pointer_sent;
    double pointer_cursor[2], pointer_vp[16];
    int pointer_window[2];
    unsigned char joy_buttons[INPUT_BUTTON_COUNT];
    float joy_axes[INPUT_AXIS_COUNT];
    int swap_windows, swap_joined; /* windows asked to join desc.swap_group; those that did */
};

extern const struct display_impl display_headless_impl;
extern const struct display_impl display_desktop_impl;
extern const struct display_impl display_stereo_impl;
extern const struct display_impl display_cave_impl;
extern const struct display_impl display_hmd_impl;
extern const struct display_impl display_orbit_impl;
extern const struct display_impl display_openxr_impl; /* built with the OpenXR loader only */

/* Shared by backends. */

/* Says why the display being created fails (display_desc.failure); the first reason given
 * stands. */
void display_fail(const struct display *d, enum display_failure why);

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

/* What must happen right before the windows swap (display_desc.before_swap). */
void display_before_swap(struct display *d);

/* A window of D's (CTX) into desc.swap_group, when one is asked for. */
void display_join_swap_group(struct display *d, struct gpu_context *ctx);

/* Tone maps IN into the whole primary window and swaps it. */
bool display_show_window(struct display *d, struct renderer *r, const struct gpu_texture *in,
                         float exposure, struct gpu_texture *scratch);

/* Makes the primary context: offscreen, the desc's context or a new EGL one; else a GLFW
 * window W x H (fullscreen on MONITOR >= 0) with quad-buffer STEREO asked for. */
bool display_open_primary(struct display *d, int w, int h, int monitor, bool stereo,
                          const char *title);
/* The same for a window WINDOW describes (size, title, stereo, and where: output name,
 * desktop rectangle or monitor index). */
bool display_open_primary_on(struct display *d, const struct gpu_context_desc *window);
/* Closes the primary context if the display made it. */
void display_close_primary(struct display *d);

/* Makes D the owner of WINDOW (a GLFWwindow): its keys, buttons, pointer, wheel and close
 * button become D's input events (display_poll_input).  The only place that installs window
 * callbacks. */
void display_watch_window(struct display *d, void *window);

/* Head trackers. */
bool display_head_tracker_init(struct display_head_tracker *h, const struct display_head *cfg,
                               const struct display_config *display);
void display_head_tracker_finish(struct display_head_tracker *h);
bool display_head_tracker_pose(struct display_head_tracker *h, double t,
                               struct display_pose *out);

#endif
