/*
 * menu: the in-world menu (Dye 2007 §4.5, Pompeii's menus) as a state machine fed by input
 * events.  A panel with six pages — Time, Fields, Transfer, Light, Quality, Probe — placed in the
 * scene, hit by the wand's ray and chosen with the trigger.  The menu edits a plain model
 * (struct menu_model) that the application owns the meaning of: it reports what changed as
 * flags and the application applies it (new time step, volume, sun, quality).
 *
 * Sliders and the transfer function editor follow the pointer while the trigger is held and
 * report their change once, on release, so a drag costs one light map rebuild, not one per
 * frame.  Buttons act on release over the same widget.
 *
 * The menu draws itself into an RGBA8 image (row 0 at the top; text baked by common/glyphs.h from
 * DejaVu Sans) that the application puts on a quad; it never reads a device and calls no GL.
 * Its pose is in "menu space": tracker metres in a CAVE or HMD, world metres on the desktop;
 * wand rays must be given in the same space.
 *
 * Must not know: devices, GL, windows, the session (it edits a plain model).
 */
#ifndef ANVIL_MENU_H
#define ANVIL_MENU_H

#include <stdbool.h>
#include <stdint.h>

#include "input/input.h"
#include "optics/optics.h"
#include "optics/transfer.h"

#define MENU_FONT_PATH "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"
#define MENU_SLOTS 4

enum menu_page { MENU_PAGE_TIME, MENU_PAGE_FIELDS, MENU_PAGE_LAYERS, MENU_PAGE_SLICES,
                 MENU_PAGE_TRANSFER, MENU_PAGE_LIGHT, MENU_PAGE_QUALITY, MENU_PAGE_PROBE,
                 MENU_PAGE_COUNT };

/* A slice as the Slices page moves it: across AXIS (0 x, 1 y, 2 z) at POSITION_M along it
 * (world metres), its normal tilted by TILT_DEG from the axis (about x for the y and z axes,
 * about y for x), through the box's centre otherwise.  menu_slice_plane makes its plane. */
struct menu_slice {
    struct transfer_slice slice;
    int axis;
    double position_m, tilt_deg;
};

/* SL's point and normal from its axis, position and tilt; BOX_CENTRE in world metres. */
void menu_slice_plane(struct menu_slice *sl, const double box_centre[3]);
/* The axis, position and tilt that come closest to SL->slice's plane (its normal's largest
 * component the axis). */
void menu_slice_from_plane(struct menu_slice *sl);

/* How the probe picks its point (session/probe.h's enum probe_mode). */
enum { MENU_PROBE_FIRST_VISIBLE, MENU_PROBE_AT_DISTANCE };

/* What the menu shows and edits. */
struct menu_model {
    /* Time */
    bool playing;
    bool loop;
    double speed;   /* steps per second */
    int step;       /* shown (or wanted) time step */
    int step_count;
    /* Fields */
    bool species_present[SPECIES_COUNT]; /* in the data: the others are greyed out */
    bool species_on[SPECIES_COUNT];
    /* Transfer */
    double species_scale[SPECIES_COUNT]; /* multiplies the species' extinction, [0, 4] */
    float species_tint[SPECIES_COUNT][3];
    bool transfer_on;                    /* the edited layer is shown; any edit of the
                                            function turns it on */
    struct transfer_function transfer;   /* the edited layer's function */
    /* Layers (the application keeps layers[layer_edited] and TRANSFER, TRANSFER_ON alike) */
    int layer_count;
    struct transfer_layer layers[TRANSFER_LAYER_MAX];
    int layer_edited;                    /* the layer the Transfer page edits */
    /* Slices */
    int slice_count;
    struct menu_slice slices[TRANSFER_SLICE_MAX];
    int slice_selected;                  /* the one the sliders move */
    double box_min_m[3], box_max_m[3];   /* the volume's box, world metres (the sliders' range) */
    bool histogram_valid;                /* the field's histogram for the step on screen */
    struct transfer_histogram histogram; /* drawn behind the curves when it is of transfer's
                                            field and range */
    int slot;                            /* saved transfer function slot, 0 .. MENU_SLOTS-1 */
    /* Light */
    double sun_azimuth, sun_elevation;   /* degrees */
    /* Quality */
    double step_m, step_max_m;           /* ray step (0 = automatic) and the slider's top */
    double lod_pixels;                   /* level of detail: steps this many pixels wide (0 off) */
    int light_resolution;                /* light map cells per axis */
    double epsilon;                      /* compression error bound */
    bool diffuse_on;                     /* multiple scattering (effects.multiple) */
    bool diffuse_possible;               /* false without a light map (effects.shadows off) */
    /* Probe */
    bool probe_on;
    int probe_mode;                      /* MENU_PROBE_* */
    double probe_threshold;              /* extinction that counts as visible, 1/m */
    double probe_distance_m, probe_distance_max_m; /* along the ray, world metres */
};

/* Change flags (menu_take_changes). */
enum {
    MENU_CHANGE_PLAYBACK = 1u << 0, /* playing, loop or speed */
    MENU_CHANGE_STEP = 1u << 1,     /* step chosen by the user */
    MENU_CHANGE_SPECIES = 1u << 2,  /* on/off, scale, tint: the volume must be made again */
    MENU_CHANGE_TRANSFER = 1u << 3, /* a layer or its function: likewise */
    MENU_CHANGE_SUN = 1u << 4,
    MENU_CHANGE_QUALITY = 1u << 5,
    MENU_ACTION_SAVE = 1u << 6,     /* save model.transfer into slot model.slot */
    MENU_ACTION_LOAD = 1u << 7,     /* load slot model.slot into model.transfer */
    MENU_ACTION_RESET_VIEW = 1u << 8,
    MENU_CHANGE_VISIBLE = 1u << 9,  /* shown or hidden */
    MENU_CHANGE_PROBE = 1u << 10,   /* on/off, mode, threshold, distance */
    MENU_ACTION_SAVE_VIEW = 1u << 11, /* "Save view": the view and look as a scene file */
    MENU_CHANGE_SLICES = 1u << 12,  /* a slice added, removed, moved, tilted or changed */
    MENU_ACTION_FRAME = 1u << 13,   /* "Frame": the view framing the whole domain again */
};

struct menu_desc {
    const char *font_path; /* NULL: MENU_FONT_PATH */
    int width, height;     /* panel image pixels; 0: 576 x 440 */
    /* Date and time of a step for the time slider's label ("" when unknown); may be NULL. */
    const char *(*step_date)(void *user, int step);
    void *user;
};

struct menu;

/* Creates a menu showing MODEL (copied), visible, on the Time page.  NULL (logged) when the
 * font cannot be read.  Destroy with menu_destroy (NULL is fine). */
struct menu *menu_create(const struct menu_desc *desc, const struct menu_model *model);
void menu_destroy(struct menu *m);

/* The model as edited; the application may change it (e.g. the step during playback) and
 * then calls menu_model_changed so the panel is drawn again. */
struct menu_model *menu_model(struct menu *m);
void menu_model_changed(struct menu *m);

/* Places the panel: centre, unit right and up vectors (the panel faces right x up, toward
 * the viewer) and width, in menu space. */
void menu_set_pose(struct menu *m, const float center[3], const float right[3],
                   const float up[3], float width);
/* The panel's corners in menu space: lower-left, lower-right, upper-right, upper-left. */
void menu_corners(const struct menu *m, float out[4][3]);
float menu_aspect(const struct menu *m); /* height / width */

/* Feeds one event.  Pose events move the pointer (the ray, already in menu space: the caller
 * converts); the trigger presses what the ray hits. */
void menu_handle(struct menu *m, const struct input_event *e);
/* The change flags gathered since the last call. */
unsigned menu_take_changes(struct menu *m);

void menu_set_visible(struct menu *m, bool visible);
bool menu_visible(const struct menu *m);
void menu_set_page(struct menu *m, enum menu_page page);
enum menu_page menu_page(const struct menu *m);
/* A status line shown at the bottom of the panel ("saved tf-1"). */
void menu_set_status(struct menu *m, const char *text);

/* The wand ray as last seen: origin, direction, and the distance to the panel along it (a
 * negative value when the ray misses the panel or the menu is hidden). */
bool menu_ray(const struct menu *m, float origin[3], float direction[3], float *hit);
/* Whether the ray is on the panel or a drag is in progress (the menu then owns the trigger). */
bool menu_captures(const struct menu *m);

/* The panel image: W x H RGBA8, row 0 at the top, drawn again when something changed.
 * GENERATION (may be NULL) increases with every redraw.  Valid until the next menu call. */
const uint8_t *menu_pixels(struct menu *m, int *w, int *h, unsigned *generation);

/* Where the widget NAME ("time.play", "transfer.canvas") lies on the current page, in panel
 * pixels [x, y, w, h]; false when the page has no such widget. */
bool menu_widget_rect(struct menu *m, const char *name, int rect[4]);
/* Whether NAME is a widget of some page (and sub-page) of the menu, shown now or not. */
bool menu_widget_known(struct menu *m, const char *name);
/* The point in menu space at (U, V) of widget NAME (for scripted aiming and tests). */
bool menu_widget_point(struct menu *m, const char *name, float u, float v, float out[3]);

/* The menu's pages' names, for docs and scripts ("time", ...). */
const char *menu_page_name(enum menu_page p);

#endif
