/*
 * input: devices turned into input events.  Sources — a scripted file of timed events (tests
 * and recorded demos) and OpenHMD controllers (the Null controllers in tests) — sit behind one
 * table and fill one queue per frame; the windows' keyboard, mouse and joystick reach the same
 * queue from the display that owns the windows (display_poll_input).  Whoever consumes the
 * events (the menu, navigation) never reads a device.  One OpenHMD context serves the whole
 * process (input_ohmd_open).  No GL, no windows.
 *
 * Spaces: a pose is in tracker metres (CAVE, HMD: the wand as the tracker reports it) or in
 * world metres (the desktop window, where the mouse ray comes from the camera).
 *
 * Must not know: GL, windows, the menu, the session.
 */
#ifndef ANVIL_INPUT_H
#define ANVIL_INPUT_H

#include <stdbool.h>

enum input_type {
    INPUT_BUTTON, /* a wand button went down or up */
    INPUT_POSE,   /* the wand's ray: position and direction */
    INPUT_AXIS,   /* a joystick axis moved (value in [-1, 1]) */
    INPUT_KEY,    /* a key was pressed (keyboard shortcuts) */
    INPUT_AIM,    /* scripted: point the ray at a named menu widget (target, u, v) */
    INPUT_DRAG,   /* the pointer moved with the left button held (u, v: pixels right, down) */
    INPUT_SCROLL, /* the wheel turned (value: notches, away from the user > 0) */
};

enum input_button {
    INPUT_BUTTON_TRIGGER, /* chooses in the menu */
    INPUT_BUTTON_GRAB,    /* held: the world follows the wand */
    INPUT_BUTTON_MENU,    /* shows or hides the menu */
    INPUT_BUTTON_RESET,   /* resets the view */
    INPUT_BUTTON_COUNT
};

enum input_axis { INPUT_AXIS_FLY, INPUT_AXIS_TURN, INPUT_AXIS_COUNT }; /* fly: forward > 0 */

enum input_space { INPUT_SPACE_TRACKER, INPUT_SPACE_WORLD };

/* Keys the menu, navigation and the frame loop know; the display maps a window's key codes
 * to these (one table, display.c), so a key means the same on every display. */
enum input_key {
    INPUT_KEY_NONE,
    INPUT_KEY_PLAY,         /* space: play / pause */
    INPUT_KEY_STEP_BACK,    /* , */
    INPUT_KEY_STEP_FORWARD, /* . */
    INPUT_KEY_MENU,         /* tab / m: show or hide the menu */
    INPUT_KEY_PAGE_NEXT,    /* ] */
    INPUT_KEY_PAGE_PREV,    /* [ */
    INPUT_KEY_QUIT,         /* Esc / q */
    INPUT_KEY_MOVE_FORWARD, /* w: the viewer moves forward */
    INPUT_KEY_MOVE_BACK,    /* s */
    INPUT_KEY_MOVE_LEFT,    /* a */
    INPUT_KEY_MOVE_RIGHT,   /* d */
    INPUT_KEY_MOVE_UP,      /* r / Page Up */
    INPUT_KEY_MOVE_DOWN,    /* f / Page Down */
    INPUT_KEY_TURN_LEFT,    /* arrow left: the view turns (the orbit camera goes round) left */
    INPUT_KEY_TURN_RIGHT,   /* arrow right */
    INPUT_KEY_TURN_UP,      /* arrow up: the storm tilts toward the viewer (its top shows) */
    INPUT_KEY_TURN_DOWN,    /* arrow down: away */
    INPUT_KEY_ZOOM_IN,      /* + / =: closer (orbit) or a larger storm (tracked displays) */
    INPUT_KEY_ZOOM_OUT,     /* - */
    INPUT_KEY_SUN_LEFT,     /* j: sun azimuth - 5 degrees */
    INPUT_KEY_SUN_RIGHT,    /* l: + 5 degrees */
    INPUT_KEY_SUN_UP,       /* i: sun elevation + 2 degrees */
    INPUT_KEY_SUN_DOWN,     /* k: - 2 degrees */
    INPUT_KEY_SCREENSHOT,   /* p: the views as PNG and PFM files */
    INPUT_KEY_BOOKMARK,     /* c: the camera as a scene file block, saved as a bookmark */
    INPUT_KEY_PATH_KEY,     /* n: the current view becomes the camera path's next key */
    INPUT_KEY_PATH_PLAY,    /* g: fly the camera path (again: stop) */
    INPUT_KEY_PROBE,        /* v: the probe on or off (the values at the wand or pointer) */
    INPUT_KEY_FRAME,        /* Shift+F: the view framing the whole domain again */
    INPUT_KEY_COUNT
};

#define INPUT_TARGET_MAX 32

struct input_event {
    enum input_type type;
    enum input_button button; /* INPUT_BUTTON */
    bool down;                /* INPUT_BUTTON */
    enum input_space space;   /* INPUT_POSE */
    float position[3];        /* INPUT_POSE: ray origin */
    float direction[3];       /* INPUT_POSE: unit ray direction */
    float up[3];              /* INPUT_POSE with HAS_UP: the wand's up, unit and across the
                                 direction (its roll about the ray) */
    bool has_up;              /* INPUT_POSE: the source knows the wand's roll */
    enum input_axis axis;     /* INPUT_AXIS */
    float value;              /* INPUT_AXIS */
    enum input_key key;       /* INPUT_KEY */
    char target[INPUT_TARGET_MAX]; /* INPUT_AIM: widget name ("time.play") */
    float u, v;               /* INPUT_AIM: where on the widget, [0, 1] each (0.5: centre);
                                 INPUT_DRAG: pixels moved right and down */
};

#define INPUT_QUEUE_MAX 256

/* The events of one frame, in order.  Events past INPUT_QUEUE_MAX are dropped (counted). */
struct input_queue {
    struct input_event events[INPUT_QUEUE_MAX];
    int count;
    int dropped;
};

void input_queue_clear(struct input_queue *q);
void input_queue_push(struct input_queue *q, const struct input_event *e);

/* ---- sources --------------------------------------------------------------------------- */

struct input_source;

/* What a frame tells the sources: its number (from 0; scripts are timed by it). */
struct input_frame {
    long frame;
};

/* Appends the events that happened up to FRAME to Q.  False when the source failed (logged). */
bool input_source_poll(struct input_source *s, const struct input_frame *frame,
                       struct input_queue *q);
/* True once a scripted source has delivered its last event (other sources never end). */
bool input_source_finished(const struct input_source *s);
const char *input_source_name(const struct input_source *s);
void input_source_destroy(struct input_source *s); /* NULL is fine */

/* The last frame a script may name: a render plays every frame up to it. */
#define INPUT_SCRIPT_FRAMES_MAX 1000000

/* A scripted input file (format in docs/menu.md): one event per line,
 *   FRAME EVENT ARGS...        e.g.  "30 button trigger down", "31 aim time.play"
 * with frames counted from 0 to INPUT_SCRIPT_FRAMES_MAX and ascending; '#' starts a comment.
 * Also "fps N" (the frame rate the script was recorded at, default 30), and a recording's
 * lines (below).  On failure logs "FILE:LINE: expected ..." and returns NULL.  Destroy with
 * input_source_destroy. */
struct input_source *input_script_open(const char *path);
/* Checks every "aim WIDGET" of the script S with KNOWN (the menu's names): false after one
 * log_error "FILE:LINE: ..." for the first one KNOWN does not know (true for other sources). */
bool input_script_check_aims(const struct input_source *s,
                             bool (*known)(const char *name, void *user), void *user);
/* The script's frame rate: a scripted run advances playback time by 1/fps per frame. */
double input_script_fps(const struct input_source *s);
/* The last frame the script names. */
long input_script_last_frame(const struct input_source *s);

/* What a recording (input_recorder) says about one frame besides its events: its clock, the
 * head pose it was drawn with (room metres), the eyes relative to that head where a runtime
 * gave them (OpenXR), the playback cursor after it.  Scripts may write these lines by hand too
 * ("12 time T DT", "12 head X Y Z QX QY QZ QW", "12 eyes X Y Z QX QY QZ QW X Y Z QX QY QZ QW",
 * left eye first, "12 cursor STEP FRACTION PLAYING"). */
struct input_script_frame {
    bool have_time;
    double time_s, dt_s;
    bool have_head;
    float head_position[3], head_rotation[4]; /* x, y, z, w */
    bool have_eyes;
    float eye_position[2][3], eye_rotation[2][4]; /* left, right; in the head's frame */
    bool have_cursor;
    int step;
    double step_acc;
    bool playing;
};

/* Fills OUT with what the script says about FRAME; false (OUT zeroed) when nothing. */
bool input_script_frame(const struct input_source *s, long frame, struct input_script_frame *out);
/* Whether any frame of the script gives the head (a recording of a tracked display). */
bool input_script_has_head(const struct input_source *s);
/* A recording's header: "recorded run" or "recorded render" (*FROM_RUN), "menu shown" or
 * "menu hidden" (*MENU_SHOWN, -1 when the script does not say). */
bool input_script_recorded(const struct input_source *s, bool *from_run, int *menu_shown);

/* ---- recordings ------------------------------------------------------------------------- */

/* A recording: every frame's events (window keys and buttons, the wand's ray, buttons and
 * stick, scripted ones) with the frame's clock, the head pose it was drawn with and the
 * playback cursor, in the script format (docs/menu.md), numbers written so that they read
 * back to the same bits.  Written to a temporary file beside PATH and renamed into place by
 * input_recorder_close. */
struct input_recorder;

struct input_record_frame {
    long frame;
    double time_s, dt_s;
    bool have_head; /* the frame was drawn: this is its head */
    float head_position[3], head_rotation[4];
    bool have_eyes; /* with the head: the eyes a runtime gave, relative to it (left, right) */
    float eye_position[2][3], eye_rotation[2][4];
    int step;
    double step_acc;
    bool playing;
};

/* Opens a recording of COMMAND ("run", "render") whose menu starts MENU_SHOWN.  NULL (logged)
 * when the file cannot be made. */
struct input_recorder *input_recorder_open(const char *path, const char *command,
                                           bool menu_shown);
/* Appends frame F with the EVENTS it handled. */
void input_recorder_frame(struct input_recorder *r, const struct input_record_frame *f,
                          const struct input_queue *events);
/* Finishes the file and renames it into place; false (logged, the temporary file removed)
 * when a write failed.  Frees R; NULL is fine. */
bool input_recorder_close(struct input_recorder *r);

/* OpenHMD controllers: the device NAME ("null": OpenHMD's Null controller, chosen by its
 * OHMD_DEVICE_FLAGS_NULL_DEVICE flag; else a product name, substring, case-insensitive) of
 * the controller class.  Its pose is the wand (tracker space, plus OFFSET metres: the
 * tracking origin in the room); its trigger/grip/menu controls become buttons.  NULL
 * (logged) when no such controller exists. */
struct input_source *input_ohmd_create(const char *name, const double offset[3]);

/* ---- OpenHMD devices: one context per process -------------------------------------------- */

struct ohmd_device; /* OpenHMD's own type (openhmd.h) */

/* Opens the device NAME ("null": the Null device of that class, chosen by its
 * OHMD_DEVICE_FLAGS_NULL_DEVICE flag; else a product name, substring, case-insensitive) of
 * DEVICE_CLASS (OHMD_DEVICE_CLASS_*, or -1 for any) in the process's one OpenHMD context,
 * made on first use.  Opening the same device again returns it again (counted).  NULL (logged
 * with the devices found) when none matches.  Close each open with input_ohmd_close; the
 * context goes with the last. */
struct ohmd_device *input_ohmd_open(const char *name, int device_class);
void input_ohmd_close(struct ohmd_device *dev); /* NULL is fine */
/* Reads the devices' new state (ohmd_ctx_update); harmless to call more than once a frame. */
void input_ohmd_update(void);
/* The product name of an open device (static storage of OpenHMD's). */
const char *input_ohmd_product(const struct ohmd_device *dev);
/* OpenHMD contexts open now: 0 or 1 (for tests). */
int input_ohmd_contexts(void);

/* Names of the buttons, keys ("trigger", "play") for scripts and messages. */
const char *input_button_name(enum input_button b);
const char *input_key_name(enum input_key k);
bool input_button_from_name(const char *name, enum input_button *out);
bool input_key_from_name(const char *name, enum input_key *out);
bool input_axis_from_name(const char *name, enum input_axis *out);

#endif
