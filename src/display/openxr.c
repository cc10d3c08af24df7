/*
 * The OpenXR backend: a headset through the OpenXR runtime the loader finds (SteamVR, Monado,
 * or whichever XR_RUNTIME_JSON names).  Built only with the OpenXR loader (HAVE_OPENXR).
 *
 * One frame, as the frame loop calls it:
 *   poll_input    the runtime's events (the session's state: ready -> begin, stopping -> end,
 *                 exiting or loss pending -> the run ends) and, while focused, the actions:
 *                 trigger, squeeze, menu, thumbstick click and the thumbstick of either hand
 *                 as the wand's buttons and axes, the aim pose of the hand that pressed last
 *                 as the wand's ray (tracker space)
 *   sample_head   xrWaitFrame, xrBeginFrame, then the head (the VIEW space in the room space)
 *                 and each eye relative to the head (xrLocateViews in the VIEW space) at the
 *                 predicted display time; the head pose goes into the frame state
 *   layout        the eyes placed from the frame state's head and the runtime's eyes
 *                 relative to it (a replay's recorded ones instead: eyes_in_head and
 *                 give_eyes), each with the runtime's asymmetric field of view as its projection
 *   present       each eye tone-mapped and copied into its swapchain's image, one projection
 *                 layer carrying the poses and fields of view the eyes were drawn with
 *
 * The room (tracker space): the runtime's STAGE space when it has one (origin on the floor),
 * else its LOCAL space placed at head.position / head.orientation.  Both are right-handed,
 * metres, +y up, like tracker space.  The runtime does the lens warp: nothing is distorted
 * here.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cglm/cglm.h>

#define XR_USE_GRAPHICS_API_OPENGL
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>
#include <openxr/openxr_reflection.h>

#include "common/log.h"
#include "display/display_impl.h"

#define EYES 2
#define HANDS 2
#define IMAGES_MAX 8
#define PRESS_ON 0.6f /* trigger and squeeze values: hysteresis between press and release */
#define PRESS_OFF 0.4f
#define DEAD_ZONE 0.15f
#define READY_WAIT_S 5.0

/* The wand's actions; the first ones are its buttons, in the order of enum input_button. */
enum action { ACT_TRIGGER, ACT_GRAB, ACT_MENU, ACT_RESET, ACT_MOVE, ACT_AIM, ACT_COUNT };

static const struct {
    const char *name, *label;
    XrActionType type;
} actions[ACT_COUNT] = {
    [ACT_TRIGGER] = {"trigger", "Choose in the menu", XR_ACTION_TYPE_FLOAT_INPUT},
    [ACT_GRAB] = {"grab", "Move the world", XR_ACTION_TYPE_FLOAT_INPUT},
    [ACT_MENU] = {"menu", "Show the menu", XR_ACTION_TYPE_BOOLEAN_INPUT},
    [ACT_RESET] = {"reset", "Reset the view", XR_ACTION_TYPE_BOOLEAN_INPUT},
    [ACT_MOVE] = {"fly", "Fly and turn", XR_ACTION_TYPE_VECTOR2F_INPUT},
    [ACT_AIM] = {"aim", "Point", XR_ACTION_TYPE_POSE_INPUT},
};

/* Suggested bindings: each profile's inputs for the actions (OpenXR 1.0, "Interaction
 * Profile Paths"); "*" stands for both hands. */
static const struct binding {
    enum action action;
    const char *path;
} simple_bindings[] =
    {
        {ACT_TRIGGER, "*/input/select/click"},
        {ACT_MENU, "*/input/menu/click"},
        {ACT_AIM, "*/input/aim/pose"},
},
  touch_bindings[] =
      {
          {ACT_TRIGGER, "*/input/trigger/value"},
          {ACT_GRAB, "*/input/squeeze/value"},
          {ACT_MENU, "/user/hand/left/input/menu/click"},
          {ACT_MENU, "/user/hand/right/input/b/click"},
          {ACT_RESET, "*/input/thumbstick/click"},
          {ACT_MOVE, "*/input/thumbstick"},
          {ACT_AIM, "*/input/aim/pose"},
},
  index_bindings[] =
      {
          {ACT_TRIGGER, "*/input/trigger/value"}, {ACT_GRAB, "*/input/squeeze/value"},
          {ACT_MENU, "*/input/b/click"},          {ACT_RESET, "*/input/thumbstick/click"},
          {ACT_MOVE, "*/input/thumbstick"},       {ACT_AIM, "*/input/aim/pose"},
},
  vive_bindings[] = {
      {ACT_TRIGGER, "*/input/trigger/value"}, {ACT_GRAB, "*/input/squeeze/click"},
      {ACT_MENU, "*/input/menu/click"},       {ACT_MOVE, "*/input/trackpad"},
      {ACT_AIM, "*/input/aim/pose"},
};

#define COUNT(a) ((int)(sizeof(a) / sizeof((a)[0])))

static const struct {
    const char *path;
    const struct binding *bindings;
    int count;
} profiles[] = {
    {"/interaction_profiles/khr/simple_controller", simple_bindings, COUNT(simple_bindings)},
    {"/interaction_profiles/oculus/touch_controller", touch_bindings, COUNT(touch_bindings)},
    {"/interaction_profiles/valve/index_controller", index_bindings, COUNT(index_bindings)},
    {"/interaction_profiles/htc/vive_controller", vive_bindings, COUNT(vive_bindings)},
};

static const char *const hand_paths[HANDS] = {"/user/hand/left", "/user/hand/right"};

struct eye_chain {
    XrSwapchain swapchain;
    uint32_t count;
    XrSwapchainImageOpenGLKHR images[IMAGES_MAX];
    int size[2];
    struct gpu_texture tonemapped; /* RGBA8, copied into the acquired image */
};

struct openxr {
    struct display base;
    XrInstance instance;
    XrDebugUtilsMessengerEXT messenger;
    PFN_xrDestroyDebugUtilsMessengerEXT destroy_messenger;
    XrSystemId system;
    XrSession session;
    XrSessionState state;
    bool running;   /* between xrBeginSession and xrEndSession */
    bool ended;     /* exiting or loss pending: the run ends */
    bool quit_sent; /* the quit event for an ended session was handed on */
    XrEnvironmentBlendMode blend;
    XrReferenceSpaceType space_type;
    XrSpace space;              /* the room */
    XrSpace view_space;         /* the head */
    struct display_pose origin; /* the pose of SPACE's origin in the room */
    struct eye_chain eyes[EYES];
    /* The frame sample_head began and present ends. */
    bool frame_open;
    XrFrameState frame;
    XrTime last_time; /* the predicted display time of the last frame begun (the controllers) */
    struct display_pose eye_in_head[EYES];
    XrFovf fov[EYES];
    bool views_valid;
    struct display_pose head;        /* the last head located, room frame */
    struct display_pose drawn[EYES]; /* the eyes as laid out: the projection layer's poses */
    struct display_pose laid[EYES];  /* ... relative to the head they were laid out from */
    bool laid_valid;
    bool given_valid;                /* a replay's eyes relative to the head, drawn instead */
    struct display_pose given[EYES]; /* of the runtime's eye_in_head */
    /* Controllers. */
    XrActionSet action_set;
    XrAction action[ACT_COUNT];
    XrPath hand[HANDS];
    XrSpace aim_space[HANDS];
    bool down[HANDS][ACT_MOVE];
    float axis[INPUT_AXIS_COUNT];
    int wand_hand; /* whose aim is the wand: the hand that pressed a button last */
    struct gpu_texture mirror;
    _Alignas(16) unsigned char binding[GPU_XR_BINDING_BYTES];
};

/* ---- names and errors ------------------------------------------------------------------ */

/* One case returning NAME, for openxr_reflection.h's lists. */
#define NAME_CASE(name, value)                                                                     \
    case name:                                                                                     \
        return #name;

static const char *result_name(XrResult r)
{
    switch (r) {
        XR_LIST_ENUM_XrResult(NAME_CASE);
    default:
        return "an unknown XrResult";
    }
}

/* The state's name without XR_SESSION_STATE_. */
static const char *state_name(XrSessionState s)
{
    const char *name = NULL;
    switch (s) {
#define STATE_CASE(state, value)                                                                   \
    case state:                                                                                    \
        name = #state;                                                                             \
        break;
        XR_LIST_ENUM_XrSessionState(STATE_CASE);
#undef STATE_CASE
    default:
        name = "XR_SESSION_STATE_UNKNOWN";
        break;
    }
    return name + strlen("XR_SESSION_STATE_");
}

/* Logs a failed CALL with its result; true when R succeeded. */
static bool ok(XrResult r, const char *call)
{
    if (XR_SUCCEEDED(r))
        return true;
    log_error("OpenXR: %s failed: %s", call, result_name(r));
    return false;
}

static XrBool32 XRAPI_CALL on_message(XrDebugUtilsMessageSeverityFlagsEXT severity,
                                      XrDebugUtilsMessageTypeFlagsEXT types,
                                      const XrDebugUtilsMessengerCallbackDataEXT *data, void *user)
{
    const char *fn = data->functionName ? data->functionName : "";
    const char *id = data->messageId ? data->messageId : "";
    if (severity & (XR_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT |
                    XR_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT))
        log_warn("OpenXR: %s %s: %s", fn, id, data->message);
    else
        log_debug("OpenXR: %s %s: %s", fn, id, data->message);
    return XR_FALSE;
}

/* ---- poses ------------------------------------------------------------------------------ */

static void from_xr(const XrPosef *p, struct display_pose *out)
{
    out->position[0] = p->position.x;
    out->position[1] = p->position.y;
    out->position[2] = p->position.z;
    out->rotation[0] = p->orientation.x;
    out->rotation[1] = p->orientation.y;
    out->rotation[2] = p->orientation.z;
    out->rotation[3] = p->orientation.w;
}

static XrPosef to_xr(const struct display_pose *p)
{
    XrPosef x;
    x.position = (XrVector3f){p->position[0], p->position[1], p->position[2]};
    x.orientation = (XrQuaternionf){p->rotation[0], p->rotation[1], p->rotation[2], p->rotation[3]};
    return x;
}

/* A pose in the runtime's room space -> the room (tracker space). */
static void to_room(const struct openxr *o, const XrPosef *p, struct display_pose *out)
{
    struct display_pose local;
    from_xr(p, &local);
    display_pose_compose(&o->origin, &local, out);
}

static XrPosef from_room(const struct openxr *o, const struct display_pose *room)
{
    struct display_pose inv, local;
    display_pose_invert(&o->origin, &inv);
    display_pose_compose(&inv, room, &local);
    return to_xr(&local);
}

static const XrPosef identity = {.orientation = {0.0f, 0.0f, 0.0f, 1.0f}};

/* ---- frames ---------------------------------------------------------------------------- */

/* A session the runtime lost ends the run, with no error of its own. */
static bool lost(struct openxr *o, XrResult r)
{
    if (r != XR_ERROR_SESSION_LOST && r != XR_ERROR_INSTANCE_LOST)
        return false;
    if (!o->ended)
        log_warn("OpenXR: the runtime lost the session: ending the run");
    o->ended = true;
    o->running = false;
    return true;
}

/* Ends the open frame without a layer (a frame begun and not drawn). */
static void end_frame_empty(struct openxr *o)
{
    if (!o->frame_open)
        return;
    XrFrameEndInfo end = {.type = XR_TYPE_FRAME_END_INFO,
                          .displayTime = o->frame.predictedDisplayTime,
                          .environmentBlendMode = o->blend};
    XrResult r = xrEndFrame(o->session, &end);
    if (!lost(o, r))
        ok(r, "xrEndFrame");
    o->frame_open = false;
}

static bool begin_frame(struct openxr *o)
{
    XrFrameWaitInfo wait = {.type = XR_TYPE_FRAME_WAIT_INFO};
    XrFrameState frame = {.type = XR_TYPE_FRAME_STATE};
    XrResult r = xrWaitFrame(o->session, &wait, &frame);
    if (lost(o, r) || !ok(r, "xrWaitFrame"))
        return false;
    XrFrameBeginInfo begin = {.type = XR_TYPE_FRAME_BEGIN_INFO};
    r = xrBeginFrame(o->session, &begin);
    if (lost(o, r) || !ok(r, "xrBeginFrame"))
        return false;
    o->frame = frame;
    o->frame_open = true;
    o->last_time = frame.predictedDisplayTime;
    return true;
}

/* ---- the session's states -------------------------------------------------------------- */

static void session_state(struct openxr *o, XrSessionState state)
{
    log_info("OpenXR: session %s", state_name(state));
    o->state = state;
    switch (state) {
    case XR_SESSION_STATE_READY: {
        XrSessionBeginInfo begin = {.type = XR_TYPE_SESSION_BEGIN_INFO,
                                    .primaryViewConfigurationType =
                                        XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO};
        o->running = ok(xrBeginSession(o->session, &begin), "xrBeginSession");
        break;
    }
    case XR_SESSION_STATE_STOPPING:
        end_frame_empty(o);
        ok(xrEndSession(o->session), "xrEndSession");
        o->running = false;
        break;
    case XR_SESSION_STATE_EXITING:
        o->ended = true;
        break;
    case XR_SESSION_STATE_LOSS_PENDING:
        if (!o->ended)
            log_warn("OpenXR: the runtime is losing the session (the headset was "
                     "disconnected?): ending the run");
        o->ended = true;
        break;
    default:
        break;
    }
}

static void log_profiles(struct openxr *o)
{
    for (int h = 0; h < HANDS; h++) {
        XrInteractionProfileState st = {.type = XR_TYPE_INTERACTION_PROFILE_STATE};
        if (!XR_SUCCEEDED(xrGetCurrentInteractionProfile(o->session, o->hand[h], &st)))
            continue;
        char path[XR_MAX_PATH_LENGTH] = "none";
        uint32_t n = 0;
        if (st.interactionProfile != XR_NULL_PATH)
            xrPathToString(o->instance, st.interactionProfile, sizeof(path), &n, path);
        log_info("OpenXR: %s: %s", hand_paths[h], path);
    }
}

/* Handles every event the runtime has queued. */
static void pump_events(struct openxr *o)
{
    for (;;) {
        XrEventDataBuffer ev = {.type = XR_TYPE_EVENT_DATA_BUFFER};
        XrResult r = xrPollEvent(o->instance, &ev);
        if (r == XR_EVENT_UNAVAILABLE)
            return;
        if (!ok(r, "xrPollEvent"))
            return;
        switch (ev.type) {
        case XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED:
            session_state(o, ((const XrEventDataSessionStateChanged *)&ev)->state);
            break;
        case XR_TYPE_EVENT_DATA_INSTANCE_LOSS_PENDING:
            log_warn("OpenXR: the runtime is going away: ending the run");
            o->ended = true;
            break;
        case XR_TYPE_EVENT_DATA_INTERACTION_PROFILE_CHANGED:
            log_profiles(o);
            break;
        case XR_TYPE_EVENT_DATA_EVENTS_LOST:
            log_warn("OpenXR: %u events were lost",
                     ((const XrEventDataEventsLost *)&ev)->lostEventCount);
            break;
        case XR_TYPE_EVENT_DATA_REFERENCE_SPACE_CHANGE_PENDING:
            log_info("OpenXR: the runtime moves its reference space (recentred)");
            break;
        default:
            break;
        }
    }
}

/* ---- creation --------------------------------------------------------------------------- */

static bool has_extension(const XrExtensionProperties *ext, uint32_t n, const char *name)
{
    for (uint32_t i = 0; i < n; i++) {
        if (strcmp(ext[i].extensionName, name) == 0)
            return true;
    }
    return false;
}

/* The instance, with the GL extension and the binding's; the debug messenger where the loader
 * offers XR_EXT_debug_utils (validation layers report through it). */
static bool create_instance(struct openxr *o, bool egl)
{
    uint32_t n = 0;
    XrResult r = xrEnumerateInstanceExtensionProperties(NULL, 0, &n, NULL);
    if (r == XR_ERROR_RUNTIME_UNAVAILABLE || r == XR_ERROR_RUNTIME_FAILURE) {
        log_error("OpenXR: no runtime could be loaded (%s): start SteamVR or monado-service, "
                  "or point XR_RUNTIME_JSON at a runtime's manifest",
                  result_name(r));
        return false;
    }
    if (!ok(r, "xrEnumerateInstanceExtensionProperties"))
        return false;
    XrExtensionProperties *ext = calloc(n ? n : 1, sizeof(*ext));
    if (!ext)
        return false;
    for (uint32_t i = 0; i < n; i++)
        ext[i].type = XR_TYPE_EXTENSION_PROPERTIES;
    if (!ok(xrEnumerateInstanceExtensionProperties(NULL, n, &n, ext),
            "xrEnumerateInstanceExtensionProperties")) {
        free(ext);
        return false;
    }
    bool gl = has_extension(ext, n, XR_KHR_OPENGL_ENABLE_EXTENSION_NAME);
    bool mndx = has_extension(ext, n, "XR_MNDX_egl_enable");
    bool debug = has_extension(ext, n, XR_EXT_DEBUG_UTILS_EXTENSION_NAME);
    free(ext);
    if (!gl) {
        log_error("OpenXR: the runtime does not offer %s (OpenGL)",
                  XR_KHR_OPENGL_ENABLE_EXTENSION_NAME);
        return false;
    }
    if (egl && !mndx) {
        log_error("OpenXR: the runtime does not offer XR_MNDX_egl_enable, which a headless EGL "
                  "context needs: run with an X display and openxr.binding = \"xlib\" (or "
                  "\"auto\")");
        return false;
    }
    const char *names[3] = {XR_KHR_OPENGL_ENABLE_EXTENSION_NAME};
    uint32_t count = 1;
    if (egl)
        names[count++] = "XR_MNDX_egl_enable";
    if (debug)
        names[count++] = XR_EXT_DEBUG_UTILS_EXTENSION_NAME;
    XrInstanceCreateInfo ci = {.type = XR_TYPE_INSTANCE_CREATE_INFO,
                               .enabledExtensionCount = count,
                               .enabledExtensionNames = names};
    snprintf(ci.applicationInfo.applicationName, sizeof(ci.applicationInfo.applicationName),
             "anvil");
    snprintf(ci.applicationInfo.engineName, sizeof(ci.applicationInfo.engineName), "anvil");
    ci.applicationInfo.applicationVersion = 1;
    ci.applicationInfo.apiVersion = XR_CURRENT_API_VERSION;
    r = xrCreateInstance(&ci, &o->instance);
    if (r == XR_ERROR_RUNTIME_UNAVAILABLE || r == XR_ERROR_RUNTIME_FAILURE) {
        log_error("OpenXR: no runtime could be started (%s): start SteamVR or monado-service, "
                  "or point XR_RUNTIME_JSON at a runtime's manifest",
                  result_name(r));
        return false;
    }
    if (!ok(r, "xrCreateInstance"))
        return false;
    XrInstanceProperties props = {.type = XR_TYPE_INSTANCE_PROPERTIES};
    if (XR_SUCCEEDED(xrGetInstanceProperties(o->instance, &props)))
        log_info("OpenXR: runtime %s %u.%u.%u", props.runtimeName,
                 (unsigned)XR_VERSION_MAJOR(props.runtimeVersion),
                 (unsigned)XR_VERSION_MINOR(props.runtimeVersion),
                 (unsigned)XR_VERSION_PATCH(props.runtimeVersion));
    if (debug) {
        PFN_xrCreateDebugUtilsMessengerEXT create = NULL;
        xrGetInstanceProcAddr(o->instance, "xrCreateDebugUtilsMessengerEXT",
                              (PFN_xrVoidFunction *)&create);
        xrGetInstanceProcAddr(o->instance, "xrDestroyDebugUtilsMessengerEXT",
                              (PFN_xrVoidFunction *)&o->destroy_messenger);
        XrDebugUtilsMessengerCreateInfoEXT mi = {
            .type = XR_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT,
            .messageSeverities = XR_DEBUG_UTILS_MESSAGE_SEVERITY_VERBOSE_BIT_EXT |
                                 XR_DEBUG_UTILS_MESSAGE_SEVERITY_INFO_BIT_EXT |
                                 XR_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                                 XR_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT,
            .messageTypes = XR_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                            XR_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                            XR_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT |
                            XR_DEBUG_UTILS_MESSAGE_TYPE_CONFORMANCE_BIT_EXT,
            .userCallback = on_message,
            .userData = o};
        if (!create || !o->destroy_messenger ||
            !XR_SUCCEEDED(create(o->instance, &mi, &o->messenger)))
            o->messenger = XR_NULL_HANDLE;
    }
    return true;
}

/* The headset, its two eyes' image sizes and the blend mode. */
static bool create_system(struct openxr *o, XrViewConfigurationView views[EYES])
{
    XrSystemGetInfo gi = {.type = XR_TYPE_SYSTEM_GET_INFO,
                          .formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY};
    XrResult r = xrGetSystem(o->instance, &gi, &o->system);
    if (r == XR_ERROR_FORM_FACTOR_UNAVAILABLE) {
        log_error("OpenXR: the runtime has no headset now (is it connected and switched on?)");
        return false;
    }
    if (!ok(r, "xrGetSystem"))
        return false;
    XrSystemProperties sp = {.type = XR_TYPE_SYSTEM_PROPERTIES};
    if (XR_SUCCEEDED(xrGetSystemProperties(o->instance, o->system, &sp)))
        log_info("OpenXR: headset %s", sp.systemName);
    uint32_t n = 0;
    if (!ok(xrEnumerateViewConfigurationViews(
                o->instance, o->system, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, 0, &n, NULL),
            "xrEnumerateViewConfigurationViews"))
        return false;
    if (n != EYES) {
        log_error("OpenXR: the stereo view configuration has %u views, not 2", n);
        return false;
    }
    for (int e = 0; e < EYES; e++)
        views[e] = (XrViewConfigurationView){.type = XR_TYPE_VIEW_CONFIGURATION_VIEW};
    if (!ok(xrEnumerateViewConfigurationViews(
                o->instance, o->system, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, n, &n, views),
            "xrEnumerateViewConfigurationViews"))
        return false;
    XrEnvironmentBlendMode modes[8];
    n = 0;
    if (!ok(xrEnumerateEnvironmentBlendModes(
                o->instance, o->system, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, 8, &n, modes),
            "xrEnumerateEnvironmentBlendModes") ||
        n == 0)
        return false;
    o->blend = modes[0];
    for (uint32_t i = 0; i < n; i++) {
        if (modes[i] == XR_ENVIRONMENT_BLEND_MODE_OPAQUE)
            o->blend = modes[i];
    }
    /* The runtime's GL version range must hold the 4.5 core context made here. */
    PFN_xrGetOpenGLGraphicsRequirementsKHR requirements = NULL;
    if (!ok(xrGetInstanceProcAddr(o->instance, "xrGetOpenGLGraphicsRequirementsKHR",
                                  (PFN_xrVoidFunction *)&requirements),
            "xrGetInstanceProcAddr(xrGetOpenGLGraphicsRequirementsKHR)"))
        return false;
    XrGraphicsRequirementsOpenGLKHR req = {.type = XR_TYPE_GRAPHICS_REQUIREMENTS_OPENGL_KHR};
    if (!ok(requirements(o->instance, o->system, &req), "xrGetOpenGLGraphicsRequirementsKHR"))
        return false;
    XrVersion gl = XR_MAKE_VERSION(4, 5, 0);
    if (req.minApiVersionSupported > gl) {
        log_error("OpenXR: the runtime needs OpenGL %u.%u; anvil makes a 4.5 context",
                  (unsigned)XR_VERSION_MAJOR(req.minApiVersionSupported),
                  (unsigned)XR_VERSION_MINOR(req.minApiVersionSupported));
        return false;
    }
    return true;
}

/* The GL context: a GLX window (xlib), a headless EGL context, or the one the desc lends. */
static bool open_context(struct openxr *o, bool egl)
{
    struct display *d = &o->base;
    if (d->desc.offscreen && d->desc.context) {
        d->context = d->desc.context;
        d->own_context = false;
        gpu_context_make_current(d->context);
        return true;
    }
    struct gpu_context_desc cd = {.backend = egl ? "egl" : "glfw",
                                  .width = d->cfg.window_size[0],
                                  .height = d->cfg.window_size[1],
                                  .title = "anvil: openxr (left eye)",
                                  .monitor = -1,
                                  .egl_config = true};
    d->context = gpu_context_create(&cd);
    d->own_context = d->context != NULL;
    if (!d->context)
        return false;
    if (!egl) {
        gpu_context_swap_interval(d->context, 0); /* the runtime paces the frames */
        if (!d->desc.offscreen)
            display_watch_window(d, gpu_context_window(d->context));
    }
    return true;
}

static bool create_session(struct openxr *o)
{
    const char *ext = gpu_context_xr_binding(o->base.context, o->binding);
    if (!ext)
        return false;
    XrSessionCreateInfo si = {
        .type = XR_TYPE_SESSION_CREATE_INFO, .next = o->binding, .systemId = o->system};
    bool created = ok(xrCreateSession(o->instance, &si, &o->session), "xrCreateSession");
    gpu_context_make_current(o->base.context); /* some runtimes change it */
    return created;
}

static bool create_spaces(struct openxr *o)
{
    const struct display_config *cfg = &o->base.cfg;
    XrReferenceSpaceType types[8];
    uint32_t n = 0;
    if (!ok(xrEnumerateReferenceSpaces(o->session, 8, &n, types), "xrEnumerateReferenceSpaces"))
        return false;
    bool stage = false;
    for (uint32_t i = 0; i < n; i++)
        stage = stage || types[i] == XR_REFERENCE_SPACE_TYPE_STAGE;
    enum display_openxr_space want = cfg->openxr.space;
    if (want == DISPLAY_OPENXR_SPACE_STAGE && !stage) {
        log_error("%s: openxr.space = \"stage\": the runtime has no stage (no room set up): "
                  "use \"local\" or \"auto\"",
                  cfg->path);
        return false;
    }
    bool use_stage = stage && want != DISPLAY_OPENXR_SPACE_LOCAL;
    o->space_type = use_stage ? XR_REFERENCE_SPACE_TYPE_STAGE : XR_REFERENCE_SPACE_TYPE_LOCAL;
    if (use_stage) {
        o->origin = (struct display_pose){.rotation = {0.0f, 0.0f, 0.0f, 1.0f}};
    } else {
        display_pose_from_euler(cfg->head.position, cfg->head.orientation_deg, &o->origin);
    }
    XrReferenceSpaceCreateInfo ri = {.type = XR_TYPE_REFERENCE_SPACE_CREATE_INFO,
                                     .referenceSpaceType = o->space_type,
                                     .poseInReferenceSpace = identity};
    if (!ok(xrCreateReferenceSpace(o->session, &ri, &o->space), "xrCreateReferenceSpace"))
        return false;
    ri.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_VIEW;
    if (!ok(xrCreateReferenceSpace(o->session, &ri, &o->view_space), "xrCreateReferenceSpace"))
        return false;
    log_info("OpenXR: the room is the runtime's %s space%s", use_stage ? "STAGE" : "LOCAL",
             use_stage ? "" : ", placed at head.position");
    return true;
}

static bool create_swapchains(struct openxr *o, const XrViewConfigurationView views[EYES])
{
    uint32_t n = 0;
    if (!ok(xrEnumerateSwapchainFormats(o->session, 0, &n, NULL), "xrEnumerateSwapchainFormats"))
        return false;
    int64_t *formats = calloc(n ? n : 1, sizeof(*formats));
    if (!formats)
        return false;
    bool listed =
        ok(xrEnumerateSwapchainFormats(o->session, n, &n, formats), "xrEnumerateSwapchainFormats");
    int64_t format = listed ? gpu_xr_swapchain_format(formats, (int)n) : 0;
    if (listed && !format) {
        char list[256] = "";
        size_t len = 0;
        for (uint32_t i = 0; i < n && len < sizeof(list); i++)
            len += (size_t)snprintf(list + len, sizeof(list) - len, "%s0x%llx", i ? ", " : "",
                                    (unsigned long long)formats[i]);
        log_error("OpenXR: the runtime offers no GL_SRGB8_ALPHA8 swapchain (formats: %s)", list);
    }
    free(formats);
    if (!format)
        return false;
    double scale = o->base.cfg.openxr.resolution_scale;
    for (int e = 0; e < EYES; e++) {
        struct eye_chain *c = &o->eyes[e];
        int w = (int)lround(views[e].recommendedImageRectWidth * scale);
        int h = (int)lround(views[e].recommendedImageRectHeight * scale);
        c->size[0] = w < 1                                 ? 1
                     : w > (int)views[e].maxImageRectWidth ? (int)views[e].maxImageRectWidth
                                                           : w;
        c->size[1] = h < 1                                  ? 1
                     : h > (int)views[e].maxImageRectHeight ? (int)views[e].maxImageRectHeight
                                                            : h;
        XrSwapchainCreateInfo sc = {.type = XR_TYPE_SWAPCHAIN_CREATE_INFO,
                                    .usageFlags = XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT |
                                                  XR_SWAPCHAIN_USAGE_TRANSFER_DST_BIT,
                                    .format = format,
                                    .sampleCount = 1,
                                    .width = (uint32_t)c->size[0],
                                    .height = (uint32_t)c->size[1],
                                    .faceCount = 1,
                                    .arraySize = 1,
                                    .mipCount = 1};
        bool made = ok(xrCreateSwapchain(o->session, &sc, &c->swapchain), "xrCreateSwapchain");
        gpu_context_make_current(o->base.context);
        if (!made)
            return false;
        uint32_t count = 0;
        if (!ok(xrEnumerateSwapchainImages(c->swapchain, 0, &count, NULL),
                "xrEnumerateSwapchainImages"))
            return false;
        if (count < 1 || count > IMAGES_MAX) {
            log_error("OpenXR: a swapchain of %u images (1 to %d expected)", count, IMAGES_MAX);
            return false;
        }
        for (uint32_t i = 0; i < count; i++)
            c->images[i] = (XrSwapchainImageOpenGLKHR){.type = XR_TYPE_SWAPCHAIN_IMAGE_OPENGL_KHR};
        if (!ok(xrEnumerateSwapchainImages(c->swapchain, count, &c->count,
                                           (XrSwapchainImageBaseHeader *)c->images),
                "xrEnumerateSwapchainImages"))
            return false;
    }
    log_info("OpenXR: eyes %dx%d and %dx%d (%.2f of the runtime's recommended size)",
             o->eyes[0].size[0], o->eyes[0].size[1], o->eyes[1].size[0], o->eyes[1].size[1], scale);
    return true;
}

static bool path(struct openxr *o, const char *text, XrPath *out)
{
    char msg[XR_MAX_PATH_LENGTH + 32];
    snprintf(msg, sizeof(msg), "xrStringToPath(\"%s\")", text);
    return ok(xrStringToPath(o->instance, text, out), msg);
}

static bool create_actions(struct openxr *o)
{
    XrActionSetCreateInfo ai = {.type = XR_TYPE_ACTION_SET_CREATE_INFO};
    snprintf(ai.actionSetName, sizeof(ai.actionSetName), "wand");
    snprintf(ai.localizedActionSetName, sizeof(ai.localizedActionSetName), "The wand");
    if (!ok(xrCreateActionSet(o->instance, &ai, &o->action_set), "xrCreateActionSet"))
        return false;
    for (int h = 0; h < HANDS; h++) {
        if (!path(o, hand_paths[h], &o->hand[h]))
            return false;
    }
    for (int a = 0; a < ACT_COUNT; a++) {
        XrActionCreateInfo ci = {.type = XR_TYPE_ACTION_CREATE_INFO,
                                 .actionType = actions[a].type,
                                 .countSubactionPaths = HANDS,
                                 .subactionPaths = o->hand};
        snprintf(ci.actionName, sizeof(ci.actionName), "%s", actions[a].name);
        snprintf(ci.localizedActionName, sizeof(ci.localizedActionName), "%s", actions[a].label);
        if (!ok(xrCreateAction(o->action_set, &ci, &o->action[a]), "xrCreateAction"))
            return false;
    }
    for (int p = 0; p < COUNT(profiles); p++) {
        XrActionSuggestedBinding suggested[32];
        uint32_t n = 0;
        for (int b = 0; b < profiles[p].count; b++) {
            const struct binding *bd = &profiles[p].bindings[b];
            for (int h = 0; h < HANDS; h++) {
                char full[XR_MAX_PATH_LENGTH];
                if (bd->path[0] == '*')
                    snprintf(full, sizeof(full), "%s%s", hand_paths[h], bd->path + 1);
                else if (h == 0)
                    snprintf(full, sizeof(full), "%s", bd->path);
                else
                    continue;
                suggested[n].action = o->action[bd->action];
                if (!path(o, full, &suggested[n].binding))
                    return false;
                n++;
            }
        }
        XrInteractionProfileSuggestedBinding sb = {
            .type = XR_TYPE_INTERACTION_PROFILE_SUGGESTED_BINDING,
            .countSuggestedBindings = n,
            .suggestedBindings = suggested};
        char msg[160];
        snprintf(msg, sizeof(msg), "xrSuggestInteractionProfileBindings(%s)", profiles[p].path);
        if (!path(o, profiles[p].path, &sb.interactionProfile) ||
            !ok(xrSuggestInteractionProfileBindings(o->instance, &sb), msg))
            return false;
    }
    XrSessionActionSetsAttachInfo at = {.type = XR_TYPE_SESSION_ACTION_SETS_ATTACH_INFO,
                                        .countActionSets = 1,
                                        .actionSets = &o->action_set};
    if (!ok(xrAttachSessionActionSets(o->session, &at), "xrAttachSessionActionSets"))
        return false;
    for (int h = 0; h < HANDS; h++) {
        XrActionSpaceCreateInfo si = {.type = XR_TYPE_ACTION_SPACE_CREATE_INFO,
                                      .action = o->action[ACT_AIM],
                                      .subactionPath = o->hand[h],
                                      .poseInActionSpace = identity};
        if (!ok(xrCreateActionSpace(o->session, &si, &o->aim_space[h]), "xrCreateActionSpace"))
            return false;
    }
    o->wand_hand = 1; /* the right hand until the left presses a button */
    return true;
}

static void sleep_s(double s)
{
    struct timespec ts = {.tv_sec = (time_t)s, .tv_nsec = (long)((s - (double)(time_t)s) * 1e9)};
    nanosleep(&ts, NULL);
}

static void openxr_destroy(struct display *d)
{
    struct openxr *o = (struct openxr *)d;
    if (d->context)
        gpu_context_make_current(d->context);
    if (o->session != XR_NULL_HANDLE) {
        end_frame_empty(o);
        /* Ask the runtime to stop; keep submitting empty frames until it says so. */
        if (o->running && XR_SUCCEEDED(xrRequestExitSession(o->session))) {
            for (int i = 0; i < 200 && o->running && !o->ended; i++) {
                pump_events(o);
                if (o->running && o->state != XR_SESSION_STATE_STOPPING && begin_frame(o))
                    end_frame_empty(o);
            }
        }
        for (int a = 0; a < HANDS; a++) {
            if (o->aim_space[a] != XR_NULL_HANDLE)
                xrDestroySpace(o->aim_space[a]);
        }
        for (int e = 0; e < EYES; e++) {
            if (o->eyes[e].swapchain != XR_NULL_HANDLE)
                xrDestroySwapchain(o->eyes[e].swapchain);
        }
        if (o->view_space != XR_NULL_HANDLE)
            xrDestroySpace(o->view_space);
        if (o->space != XR_NULL_HANDLE)
            xrDestroySpace(o->space);
        xrDestroySession(o->session);
    }
    if (o->action_set != XR_NULL_HANDLE)
        xrDestroyActionSet(o->action_set);
    if (o->messenger != XR_NULL_HANDLE)
        o->destroy_messenger(o->messenger);
    if (o->instance != XR_NULL_HANDLE)
        xrDestroyInstance(o->instance);
    if (d->context) {
        gpu_context_make_current(d->context);
        for (int e = 0; e < EYES; e++)
            gpu_texture_finish(&o->eyes[e].tonemapped);
        gpu_texture_finish(&o->mirror);
    }
    display_close_primary(d);
    free(o);
}

static struct display *openxr_create(const struct display *base)
{
    struct openxr *o = calloc(1, sizeof(*o));
    if (!o)
        return NULL;
    o->base = *base;
    struct display *d = &o->base;
    const struct display_config *cfg = &d->cfg;
    /* The binding: the lent context's kind, else as configured. */
    enum display_openxr_binding binding = cfg->openxr.binding;
    if (d->desc.offscreen && d->desc.context)
        binding = gpu_context_window(d->desc.context) ? DISPLAY_OPENXR_BINDING_XLIB
                                                      : DISPLAY_OPENXR_BINDING_EGL;
    else if (binding == DISPLAY_OPENXR_BINDING_AUTO) {
        const char *x = getenv("DISPLAY");
        binding = x && *x ? DISPLAY_OPENXR_BINDING_XLIB : DISPLAY_OPENXR_BINDING_EGL;
    }
    bool egl = binding == DISPLAY_OPENXR_BINDING_EGL;
    if (cfg->head.source != DISPLAY_HEAD_FIXED)
        log_warn("%s: head.source = \"%s\" is not used: the head is the headset's", cfg->path,
                 display_head_source_name(cfg->head.source));
    XrViewConfigurationView views[EYES];
    if (!create_instance(o, egl) || !create_system(o, views) || !open_context(o, egl) ||
        !create_session(o) || !create_spaces(o) || !create_swapchains(o, views) ||
        !create_actions(o))
        goto error;
    log_info("OpenXR: %s binding", egl ? "EGL (XR_MNDX_egl_enable)" : "Xlib (GLX window)");
    /* Until the runtime locates them: the eyes at the configured separation, 90 degrees. */
    display_pose_from_euler(cfg->head.position, cfg->head.orientation_deg, &o->head);
    for (int e = 0; e < EYES; e++) {
        float x = (float)((e == 0 ? -0.5 : 0.5) * cfg->eye_separation);
        o->eye_in_head[e] = (struct display_pose){.position = {x, 0.0f, 0.0f},
                                                  .rotation = {0.0f, 0.0f, 0.0f, 1.0f}};
        o->fov[e] = (XrFovf){-0.785398f, 0.785398f, 0.785398f, -0.785398f};
    }
    /* A runtime with a headset in place gets ready at once; a still render needs it to. */
    for (double waited = 0.0; !o->running && !o->ended && waited < READY_WAIT_S; waited += 0.01) {
        pump_events(o);
        if (!o->running)
            sleep_s(0.01);
    }
    if (!o->running) {
        if (d->desc.offscreen) {
            log_error("OpenXR: the session did not get ready within %.0f s (state %s)",
                      READY_WAIT_S, state_name(o->state));
            goto error;
        }
        log_info("OpenXR: waiting for the session to get ready (state %s)", state_name(o->state));
    }
    return d;

error:
    openxr_destroy(d);
    return NULL;
}

/* ---- per frame -------------------------------------------------------------------------- */

static bool openxr_sample_head(struct display *d, double t, struct display_pose *head)
{
    struct openxr *o = (struct openxr *)d;
    end_frame_empty(o); /* begun for a frame that was not drawn */
    pump_events(o);
    if (o->ended && d->desc.offscreen) {
        log_error("OpenXR: the session ended before the render did");
        return false;
    }
    o->views_valid = false;
    if (o->running && begin_frame(o)) {
        XrTime time = o->frame.predictedDisplayTime;
        XrSpaceLocation loc = {.type = XR_TYPE_SPACE_LOCATION};
        if (ok(xrLocateSpace(o->view_space, o->space, time, &loc), "xrLocateSpace") &&
            (loc.locationFlags & XR_SPACE_LOCATION_ORIENTATION_VALID_BIT)) {
            struct display_pose p;
            to_room(o, &loc.pose, &p);
            if (!(loc.locationFlags & XR_SPACE_LOCATION_POSITION_VALID_BIT))
                memcpy(p.position, o->head.position, sizeof(p.position));
            o->head = p;
        }
        XrViewLocateInfo li = {.type = XR_TYPE_VIEW_LOCATE_INFO,
                               .viewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO,
                               .displayTime = time,
                               .space = o->view_space};
        XrViewState vs = {.type = XR_TYPE_VIEW_STATE};
        XrView views[EYES] = {{.type = XR_TYPE_VIEW}, {.type = XR_TYPE_VIEW}};
        uint32_t n = 0;
        if (ok(xrLocateViews(o->session, &li, &vs, EYES, &n, views), "xrLocateViews") &&
            n == EYES && (vs.viewStateFlags & XR_VIEW_STATE_ORIENTATION_VALID_BIT)) {
            for (int e = 0; e < EYES; e++) {
                from_xr(&views[e].pose, &o->eye_in_head[e]);
                o->fov[e] = views[e].fov;
            }
            o->views_valid = true;
        }
    }
    *head = o->head;
    return true;
}

static bool openxr_layout(struct display *d, const struct display_pose *head,
                          const struct display_navigation *nav, const struct display_camera *camera)
{
    struct openxr *o = (struct openxr *)d;
    float nav_m[16];
    display_navigation_matrix(nav, nav_m);
    bool draw = o->frame_open && o->frame.shouldRender && o->views_valid;
    for (int e = 0; e < EYES; e++) {
        struct view *v = &d->set.views[e];
        snprintf(v->name, sizeof(v->name), "%s", e == 0 ? "left" : "right");
        v->wall = 0;
        v->eye = e == 0 ? VIEW_EYE_LEFT : VIEW_EYE_RIGHT;
        v->visible = draw;
        v->rv.width = o->eyes[e].size[0];
        v->rv.height = o->eyes[e].size[1];
        /* The eye from the frame state's head and the eye relative to it (the runtime's, or a
         * recording's): a recording keeps both, and its replay draws the same eye. */
        o->laid[e] = o->given_valid ? o->given[e] : o->eye_in_head[e];
        display_pose_compose(head, &o->laid[e], &o->drawn[e]);
        memcpy(v->eye_tracker, o->drawn[e].position, sizeof(v->eye_tracker));
        display_pose_view(&o->drawn[e], nav_m, v->rv.view);
        const XrFovf *f = &o->fov[e];
        display_fov_projection(f->angleLeft, f->angleRight, f->angleUp, f->angleDown,
                               (float)d->cfg.near_m, (float)d->cfg.far_m, v->rv.proj);
    }
    d->set.count = EYES;
    o->laid_valid = true;
    return true;
}

static bool openxr_eyes_in_head(const struct display *d, struct display_pose out[2])
{
    const struct openxr *o = (const struct openxr *)d;
    if (!o->laid_valid)
        return false;
    memcpy(out, o->laid, sizeof(o->laid));
    return true;
}

static void openxr_give_eyes(struct display *d, const struct display_pose eyes[2])
{
    struct openxr *o = (struct openxr *)d;
    o->given_valid = eyes != NULL;
    if (eyes)
        memcpy(o->given, eyes, sizeof(o->given));
}

/* Copies eye E's tone-mapped image into its swapchain's next image. */
static bool submit_eye(struct openxr *o, struct renderer *r, int e, float exposure,
                       XrCompositionLayerProjectionView *out)
{
    struct eye_chain *c = &o->eyes[e];
    const struct gpu_texture *in = &o->base.set.views[e].target;
    if (!renderer_tonemap(r, in, exposure, &c->tonemapped))
        return false;
    uint32_t index = 0;
    XrSwapchainImageAcquireInfo ai = {.type = XR_TYPE_SWAPCHAIN_IMAGE_ACQUIRE_INFO};
    XrSwapchainImageWaitInfo wi = {.type = XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO,
                                   .timeout = XR_INFINITE_DURATION};
    XrSwapchainImageReleaseInfo ri = {.type = XR_TYPE_SWAPCHAIN_IMAGE_RELEASE_INFO};
    if (!ok(xrAcquireSwapchainImage(c->swapchain, &ai, &index), "xrAcquireSwapchainImage"))
        return false;
    bool waited = ok(xrWaitSwapchainImage(c->swapchain, &wi), "xrWaitSwapchainImage");
    gpu_context_make_current(o->base.context);
    if (!waited)
        return false;
    gpu_texture_copy_into(&c->tonemapped, c->images[index].image);
    if (!ok(xrReleaseSwapchainImage(c->swapchain, &ri), "xrReleaseSwapchainImage"))
        return false;
    gpu_context_make_current(o->base.context);
    *out = (XrCompositionLayerProjectionView){
        .type = XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW,
        .pose = from_room(o, &o->drawn[e]),
        .fov = o->fov[e],
        .subImage = {.swapchain = c->swapchain,
                     .imageRect = {.offset = {0, 0}, .extent = {c->size[0], c->size[1]}},
                     .imageArrayIndex = 0}};
    return true;
}

static bool openxr_present(struct display *d, struct renderer *r, float exposure)
{
    struct openxr *o = (struct openxr *)d;
    if (!o->frame_open)
        return true;
    bool drawn = d->set.count == EYES;
    for (int e = 0; e < EYES && drawn; e++)
        drawn = d->set.views[e].visible && d->set.views[e].target.id;
    XrCompositionLayerProjectionView views[EYES];
    XrCompositionLayerProjection layer = {.type = XR_TYPE_COMPOSITION_LAYER_PROJECTION,
                                          .space = o->space,
                                          .viewCount = EYES,
                                          .views = views};
    const XrCompositionLayerBaseHeader *layers[1] = {(const XrCompositionLayerBaseHeader *)&layer};
    for (int e = 0; e < EYES && drawn; e++) {
        if (!submit_eye(o, r, e, exposure, &views[e])) {
            end_frame_empty(o);
            return false;
        }
    }
    XrFrameEndInfo end = {.type = XR_TYPE_FRAME_END_INFO,
                          .displayTime = o->frame.predictedDisplayTime,
                          .environmentBlendMode = o->blend,
                          .layerCount = drawn ? 1 : 0,
                          .layers = drawn ? layers : NULL};
    o->frame_open = false;
    XrResult res = xrEndFrame(o->session, &end);
    if (lost(o, res))
        return true;
    if (!ok(res, "xrEndFrame"))
        return false;
    gpu_context_make_current(d->context);
    /* The window (xlib) mirrors the left eye. */
    if (drawn && !d->desc.offscreen && gpu_context_window(d->context))
        return display_show_window(d, r, &d->set.views[0].target, exposure, &o->mirror);
    return true;
}

/* ---- controllers ------------------------------------------------------------------------ */

static float float_state(struct openxr *o, enum action a, int h, bool *active)
{
    XrActionStateGetInfo gi = {
        .type = XR_TYPE_ACTION_STATE_GET_INFO, .action = o->action[a], .subactionPath = o->hand[h]};
    if (actions[a].type == XR_ACTION_TYPE_BOOLEAN_INPUT) {
        XrActionStateBoolean st = {.type = XR_TYPE_ACTION_STATE_BOOLEAN};
        bool got = XR_SUCCEEDED(xrGetActionStateBoolean(o->session, &gi, &st));
        *active = got && st.isActive;
        return *active && st.currentState ? 1.0f : 0.0f;
    }
    XrActionStateFloat st = {.type = XR_TYPE_ACTION_STATE_FLOAT};
    bool got = XR_SUCCEEDED(xrGetActionStateFloat(o->session, &gi, &st));
    *active = got && st.isActive;
    return *active ? st.currentState : 0.0f;
}

static void push_button(struct input_queue *q, enum input_button b, bool down)
{
    input_queue_push(q, &(struct input_event){.type = INPUT_BUTTON, .button = b, .down = down});
}

/* Releases whatever is held (focus went elsewhere). */
static void release_all(struct openxr *o, struct input_queue *q)
{
    for (int h = 0; h < HANDS; h++) {
        for (int a = 0; a < ACT_MOVE; a++) {
            if (o->down[h][a])
                push_button(q, (enum input_button)a, false);
            o->down[h][a] = false;
        }
    }
    for (int a = 0; a < INPUT_AXIS_COUNT; a++) {
        if (o->axis[a] != 0.0f)
            input_queue_push(q,
                             &(struct input_event){.type = INPUT_AXIS, .axis = (enum input_axis)a});
        o->axis[a] = 0.0f;
    }
}

/* The wand's ray from hand H's aim pose, in the room. */
static void push_aim(struct openxr *o, int h, struct input_queue *q)
{
    if (o->last_time == 0)
        return;
    XrSpaceLocation loc = {.type = XR_TYPE_SPACE_LOCATION};
    const XrSpaceLocationFlags need =
        XR_SPACE_LOCATION_POSITION_VALID_BIT | XR_SPACE_LOCATION_ORIENTATION_VALID_BIT;
    if (!XR_SUCCEEDED(xrLocateSpace(o->aim_space[h], o->space, o->last_time, &loc)) ||
        (loc.locationFlags & need) != need)
        return;
    struct display_pose p;
    to_room(o, &loc.pose, &p);
    versor qr;
    vec3 dir;
    memcpy(qr, p.rotation, sizeof(qr));
    glm_quat_rotatev(qr, (vec3){0.0f, 0.0f, -1.0f}, dir); /* the aim pose points along -z */
    vec3 up;
    glm_quat_rotatev(qr, (vec3){0.0f, 1.0f, 0.0f}, up);
    struct input_event e = {.type = INPUT_POSE, .space = INPUT_SPACE_TRACKER, .has_up = true};
    memcpy(e.position, p.position, sizeof(e.position));
    memcpy(e.direction, dir, sizeof(e.direction));
    memcpy(e.up, up, sizeof(e.up));
    input_queue_push(q, &e);
}

static void poll_actions(struct openxr *o, struct input_queue *q)
{
    XrActiveActionSet active = {.actionSet = o->action_set, .subactionPath = XR_NULL_PATH};
    XrActionsSyncInfo si = {
        .type = XR_TYPE_ACTIONS_SYNC_INFO, .countActiveActionSets = 1, .activeActionSets = &active};
    if (!ok(xrSyncActions(o->session, &si), "xrSyncActions"))
        return;
    /* Buttons first into a list of their own: the ray goes ahead of them, so that a press
     * acts where the hand points, and the hand that pressed carries the ray. */
    struct input_event pressed[HANDS * ACT_MOVE];
    int n = 0;
    for (int h = 0; h < HANDS; h++) {
        for (int a = 0; a < ACT_MOVE; a++) {
            bool bound;
            float v = float_state(o, (enum action)a, h, &bound);
            bool down = o->down[h][a] ? v > PRESS_OFF : v >= PRESS_ON;
            if (down == o->down[h][a])
                continue;
            o->down[h][a] = down;
            if (down)
                o->wand_hand = h;
            pressed[n++] = (struct input_event){
                .type = INPUT_BUTTON, .button = (enum input_button)a, .down = down};
        }
    }
    push_aim(o, o->wand_hand, q);
    for (int i = 0; i < n; i++)
        input_queue_push(q, &pressed[i]);
    /* The stick of whichever hand pushes it further: up flies forward, sideways turns. */
    XrVector2f stick = {0.0f, 0.0f};
    for (int h = 0; h < HANDS; h++) {
        XrActionStateGetInfo gi = {.type = XR_TYPE_ACTION_STATE_GET_INFO,
                                   .action = o->action[ACT_MOVE],
                                   .subactionPath = o->hand[h]};
        XrActionStateVector2f st = {.type = XR_TYPE_ACTION_STATE_VECTOR2F};
        if (XR_SUCCEEDED(xrGetActionStateVector2f(o->session, &gi, &st)) && st.isActive &&
            hypotf(st.currentState.x, st.currentState.y) > hypotf(stick.x, stick.y))
            stick = st.currentState;
    }
    float want[INPUT_AXIS_COUNT] = {[INPUT_AXIS_FLY] = stick.y, [INPUT_AXIS_TURN] = stick.x};
    for (int a = 0; a < INPUT_AXIS_COUNT; a++) {
        float v = fabsf(want[a]) < DEAD_ZONE ? 0.0f : want[a];
        if (v != o->axis[a]) {
            o->axis[a] = v;
            input_queue_push(q, &(struct input_event){
                                    .type = INPUT_AXIS, .axis = (enum input_axis)a, .value = v});
        }
    }
}

static void openxr_poll_input(struct display *d, double timeout_s, struct input_queue *q)
{
    struct openxr *o = (struct openxr *)d;
    pump_events(o);
    if (o->running && o->state == XR_SESSION_STATE_FOCUSED)
        poll_actions(o, q);
    else
        release_all(o, q);
    if (o->ended && !o->quit_sent) {
        d->should_close = true;
        o->quit_sent = true;
        input_queue_push(q, &(struct input_event){.type = INPUT_KEY, .key = INPUT_KEY_QUIT});
    }
    if (!o->running && !o->ended)
        sleep_s(timeout_s > 0.01 ? timeout_s : 0.01); /* no frames to pace the loop */
}

const struct display_impl display_openxr_impl = {
    .name = "openxr",
    .description = "a headset through an OpenXR runtime (SteamVR, Monado, ...): the "
                   "runtime's per-eye poses and fields of view, its controllers as the wand, "
                   "its lens warp",
    .create = openxr_create,
    .destroy = openxr_destroy,
    .layout = openxr_layout,
    .present = openxr_present,
    .sample_head = openxr_sample_head,
    .eyes_in_head = openxr_eyes_in_head,
    .give_eyes = openxr_give_eyes,
    .poll_input = openxr_poll_input,
};
