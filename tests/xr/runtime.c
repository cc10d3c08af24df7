/*
 * The test runtime: a small OpenXR runtime, a shared library the OpenXR loader loads through
 * the manifest that XR_RUNTIME_JSON names.  It serves one headset with scripted head poses,
 * eyes and controller input (the script format is in runtime.h), makes the swapchain images as
 * GL textures in the application's context, and keeps the images the application submits.
 *
 * It implements the entry points anvil's openxr display calls and checks what a runtime must
 * check: call order (session states, frames, swapchain images), handles, layers, bindings
 * against the interaction profiles' paths (OpenXR 1.0, "Interaction Profile Paths").  What it
 * finds wrong is a fault: counted, printed to stderr and reported.  The Khronos validation
 * layer, loaded between the application and this library, checks the application's side.
 *
 * What it does not do: time (frames come at once, 90 Hz display times), tracking, lens
 * distortion, composition; one instance and one session at a time.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cglm/cglm.h>
#include <epoxy/egl.h>
#include <epoxy/gl.h>
#include <epoxy/glx.h>

#define XR_USE_GRAPHICS_API_OPENGL
#define XR_USE_PLATFORM_EGL
#define XR_USE_PLATFORM_XLIB
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>
#include <openxr/openxr_reflection.h>

#include "runtime.h"

#define EXPORT __attribute__((visibility("default")))
#define PERIOD_NS 11111111
#define TIME0_NS 1000000000LL
#define IMAGES 3
#define PATHS_MAX 512
#define EVENTS_MAX 4096
#define QUEUE_MAX 64
#define ACTIONS_MAX 32
#define BINDINGS_MAX 256
#define SPACES_MAX 32

/* ---- the loader interface (OpenXR loader specification, "Runtime Interface Negotiation") - */

enum { LOADER_INFO = 1, RUNTIME_REQUEST = 3 };

struct negotiate_loader_info {
    int structType;
    uint32_t structVersion;
    size_t structSize;
    uint32_t minInterfaceVersion, maxInterfaceVersion;
    XrVersion minApiVersion, maxApiVersion;
};

struct negotiate_runtime_request {
    int structType;
    uint32_t structVersion;
    size_t structSize;
    uint32_t runtimeInterfaceVersion;
    XrVersion runtimeApiVersion;
    PFN_xrGetInstanceProcAddr getInstanceProcAddr;
};

/* ---- state ------------------------------------------------------------------------------ */

struct pose {
    vec3 p;
    versor q;
};

enum event_kind { EV_HEAD, EV_AIM, EV_INPUT, EV_EXIT, EV_LOSE };

struct script_event {
    long frame;
    enum event_kind kind;
    int hand;
    struct pose pose;
    char path[128];
    float v[2];
    bool fired;
};

struct action {
    XrActionType type;
    char name[XR_MAX_ACTION_NAME_SIZE];
    XrPath subaction[4];
    int subactions;
    bool live;
};

struct binding {
    XrPath profile, path;
    struct action *action;
};

struct space {
    bool live;
    bool reference;
    XrReferenceSpaceType type;
    struct action *action;
    XrPath subaction;
    struct pose offset;
};

struct swapchain {
    bool live;
    int64_t format;
    int width, height;
    GLuint tex[IMAGES];
    int next, acquired, waited; /* next to acquire; acquired and not released; waited index */
    int released;               /* the image released last, -1 none */
    bool released_since_frame;
};

static struct {
    /* Configuration from the script. */
    int size[2];
    float fov_deg[2][4];
    vec3 eye[2];
    bool stage;
    vec3 local;
    char profile_path[128];
    struct script_event events[EVENTS_MAX];
    int event_count;
    bool loaded;
    /* Objects: one instance, one session, handles are addresses inside this struct. */
    bool instance_live, session_live;
    bool mndx, debug_utils, gl_requirements;
    XrSessionState state;
    bool running, exit_requested, lost;
    XrSessionState queue[QUEUE_MAX];
    int queue_head, queue_count;
    bool profile_event;
    char paths[PATHS_MAX][XR_MAX_PATH_LENGTH];
    int path_count;
    bool action_set_live, attached;
    struct action actions[ACTIONS_MAX];
    struct binding bindings[BINDINGS_MAX];
    int binding_count;
    struct space spaces[SPACES_MAX];
    struct swapchain swapchains[4];
    /* The application's context. */
    bool egl;
    EGLDisplay egl_display;
    EGLContext egl_context;
    Display *x_display;
    GLXDrawable glx_drawable;
    GLXContext glx_context;
    /* Frames. */
    long waits;         /* xrWaitFrame calls */
    bool waited, begun; /* a frame waited for and not begun; begun and not ended */
    XrTime frame_time;  /* the predicted display time of the frame waited last */
    /* Inputs as of the last xrSyncActions. */
    long sync_frame;
    bool synced;
    /* What tests read. */
    struct anvil_xr_test_report report;
    uint8_t *image[2];
    int image_size[2][2];
} rt;

static void fault(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

static void fault(const char *fmt, ...)
{
    char msg[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof(msg), fmt, ap);
    va_end(ap);
    fprintf(stderr, "anvil test runtime: fault: %s\n", msg);
    if (rt.report.faults < ANVIL_XR_TEST_FAULTS_KEPT)
        snprintf(rt.report.fault[rt.report.faults], sizeof(rt.report.fault[0]), "%s", msg);
    rt.report.faults++;
}

/* One case returning NAME, for openxr_reflection.h's lists. */
#define NAME_CASE(name, value)                                                                     \
    case name:                                                                                     \
        return #name;

static const char *result_name(XrResult r)
{
    switch (r) {
        XR_LIST_ENUM_XrResult(NAME_CASE);
    default:
        return NULL;
    }
}

static const char *type_name(XrStructureType t)
{
    switch (t) {
        XR_LIST_ENUM_XrStructureType(NAME_CASE);
    default:
        return NULL;
    }
}

static const char *state_name(XrSessionState s)
{
    switch (s) {
        XR_LIST_ENUM_XrSessionState(NAME_CASE);
    default:
        return "XR_SESSION_STATE_?";
    }
}

/* ---- the script ------------------------------------------------------------------------- */

static void defaults(void)
{
    rt.size[0] = 96;
    rt.size[1] = 80;
    for (int e = 0; e < 2; e++) {
        const float f[4] = {-45.0f, 45.0f, 45.0f, -45.0f};
        memcpy(rt.fov_deg[e], f, sizeof(f));
        rt.eye[e][0] = e == 0 ? -0.032f : 0.032f;
        rt.eye[e][1] = rt.eye[e][2] = 0.0f;
    }
    rt.stage = true;
    rt.local[0] = 0.0f;
    rt.local[1] = 1.6f;
    rt.local[2] = 0.0f;
    snprintf(rt.profile_path, sizeof(rt.profile_path), "%s",
             "/interaction_profiles/khr/simple_controller");
}

static void euler(float yaw, float pitch, float roll, versor out)
{
    versor qy, qx, qz;
    glm_quatv(qy, glm_rad(yaw), (vec3){0.0f, 1.0f, 0.0f});
    glm_quatv(qx, glm_rad(pitch), (vec3){1.0f, 0.0f, 0.0f});
    glm_quatv(qz, glm_rad(roll), (vec3){0.0f, 0.0f, 1.0f});
    glm_quat_mul(qy, qx, out);
    glm_quat_mul(out, qz, out);
    glm_quat_normalize(out);
}

/* The rotation that turns -z toward DIR (y staying up as far as it can). */
static void look(const vec3 dir, versor out)
{
    vec3 d;
    glm_vec3_normalize_to((float *)dir, d);
    float yaw = atan2f(-d[0], -d[2]);
    float pitch = asinf(d[1]);
    euler(glm_deg(yaw), glm_deg(pitch), 0.0f, out);
}

static int eye_index(const char *s)
{
    return strcmp(s, "left") == 0 ? 0 : strcmp(s, "right") == 0 ? 1 : -1;
}

static bool script_line(char *line)
{
    char *hash = strchr(line, '#');
    if (hash)
        *hash = '\0';
    char w[6][128] = {{0}};
    float f[8] = {0};
    char *tok[16];
    int n = 0;
    for (char *t = strtok(line, " \t\r\n"); t && n < 16; t = strtok(NULL, " \t\r\n"))
        tok[n++] = t;
    if (n == 0)
        return true;
    char *end;
    long frame = strtol(tok[0], &end, 10);
    bool timed = *end == '\0';
    int a = timed ? 1 : 0;
    if (a >= n)
        return false;
    const char *cmd = tok[a];
    int args = n - a - 1;
    char **arg = tok + a + 1;
    for (int i = 0; i < args && i < 8; i++) {
        f[i] = strtof(arg[i], NULL);
        if (i < 6)
            snprintf(w[i], sizeof(w[i]), "%s", arg[i]);
    }
    if (!timed) {
        if (strcmp(cmd, "size") == 0 && args == 2) {
            rt.size[0] = (int)f[0];
            rt.size[1] = (int)f[1];
        } else if (strcmp(cmd, "fov") == 0 && args == 5 && eye_index(w[0]) >= 0) {
            for (int i = 0; i < 4; i++)
                rt.fov_deg[eye_index(w[0])][i] = strtof(arg[1 + i], NULL);
        } else if (strcmp(cmd, "eye") == 0 && args == 4 && eye_index(w[0]) >= 0) {
            for (int i = 0; i < 3; i++)
                rt.eye[eye_index(w[0])][i] = strtof(arg[1 + i], NULL);
        } else if (strcmp(cmd, "stage") == 0 && args == 1) {
            rt.stage = strcmp(w[0], "on") == 0;
        } else if (strcmp(cmd, "local") == 0 && args == 3) {
            glm_vec3_copy((vec3){f[0], f[1], f[2]}, rt.local);
        } else if (strcmp(cmd, "profile") == 0 && args == 1) {
            snprintf(rt.profile_path, sizeof(rt.profile_path), "%s", w[0]);
        } else {
            return false;
        }
        return true;
    }
    if (rt.event_count == EVENTS_MAX)
        return false;
    struct script_event *e = &rt.events[rt.event_count];
    memset(e, 0, sizeof(*e));
    e->frame = frame;
    if (strcmp(cmd, "head") == 0 && args == 6) {
        e->kind = EV_HEAD;
        glm_vec3_copy((vec3){f[0], f[1], f[2]}, e->pose.p);
        euler(f[3], f[4], f[5], e->pose.q);
    } else if (strcmp(cmd, "aim") == 0 && args == 7 && eye_index(w[0]) >= 0) {
        e->kind = EV_AIM;
        e->hand = eye_index(w[0]);
        float v[6];
        for (int i = 0; i < 6; i++)
            v[i] = strtof(arg[1 + i], NULL);
        glm_vec3_copy((vec3){v[0], v[1], v[2]}, e->pose.p);
        look((vec3){v[3] - v[0], v[4] - v[1], v[5] - v[2]}, e->pose.q);
    } else if (strcmp(cmd, "input") == 0 && (args == 2 || args == 3)) {
        e->kind = EV_INPUT;
        snprintf(e->path, sizeof(e->path), "%s", w[0]);
        e->v[0] = strtof(arg[1], NULL);
        e->v[1] = args == 3 ? strtof(arg[2], NULL) : 0.0f;
    } else if (strcmp(cmd, "exit") == 0 && args == 0) {
        e->kind = EV_EXIT;
    } else if (strcmp(cmd, "lose") == 0 && args == 0) {
        e->kind = EV_LOSE;
    } else {
        return false;
    }
    rt.event_count++;
    return true;
}

static bool script_text(const char *text)
{
    char *copy = strdup(text);
    if (!copy)
        return false;
    bool good = true;
    for (char *p = copy; p && *p;) {
        char *nl = strchr(p, '\n');
        if (nl)
            *nl = '\0';
        char line[1024];
        snprintf(line, sizeof(line), "%s", p);
        if (!script_line(line)) {
            fprintf(stderr, "anvil test runtime: bad script line: %s\n", p);
            good = false;
        }
        p = nl ? nl + 1 : NULL;
    }
    free(copy);
    return good;
}

static void load_script(void)
{
    if (rt.loaded)
        return;
    rt.loaded = true;
    defaults();
    const char *file = getenv("ANVIL_XR_TEST_SCRIPT");
    if (!file)
        return;
    FILE *f = fopen(file, "r");
    if (!f) {
        fprintf(stderr, "anvil test runtime: cannot read %s\n", file);
        return;
    }
    char line[1024];
    while (fgets(line, sizeof(line), f)) {
        char copy[1024];
        snprintf(copy, sizeof(copy), "%s", line);
        if (!script_line(copy))
            fprintf(stderr, "anvil test runtime: %s: bad line: %s", file, line);
    }
    fclose(f);
}

/* The scripted state at frame K. */
static void head_at(long k, struct pose *out)
{
    glm_vec3_copy((vec3){0.0f, 1.6f, 0.0f}, out->p);
    glm_quat_identity(out->q);
    for (int i = 0; i < rt.event_count; i++) {
        if (rt.events[i].kind == EV_HEAD && rt.events[i].frame <= k)
            *out = rt.events[i].pose;
    }
}

static void aim_at(long k, int hand, struct pose *out)
{
    glm_vec3_copy((vec3){hand == 0 ? -0.2f : 0.2f, 1.2f, -0.3f}, out->p);
    glm_quat_identity(out->q);
    for (int i = 0; i < rt.event_count; i++) {
        if (rt.events[i].kind == EV_AIM && rt.events[i].hand == hand && rt.events[i].frame <= k)
            *out = rt.events[i].pose;
    }
}

static bool input_at(long k, const char *path, float v[2])
{
    bool found = false;
    v[0] = v[1] = 0.0f;
    for (int i = 0; i < rt.event_count; i++) {
        const struct script_event *e = &rt.events[i];
        if (e->kind == EV_INPUT && e->frame <= k && strcmp(e->path, path) == 0) {
            v[0] = e->v[0];
            v[1] = e->v[1];
            found = true;
        }
    }
    return found;
}

static long frame_of(XrTime t)
{
    long k = (long)llround((double)(t - TIME0_NS) / PERIOD_NS) - 1;
    return k < 0 ? 0 : k;
}

/* ---- poses ------------------------------------------------------------------------------ */

static void compose(const struct pose *a, const struct pose *b, struct pose *out)
{
    struct pose r;
    glm_quat_rotatev((float *)a->q, (float *)b->p, r.p);
    glm_vec3_add(r.p, (float *)a->p, r.p);
    glm_quat_mul((float *)a->q, (float *)b->q, r.q);
    glm_quat_normalize(r.q);
    *out = r;
}

static void invert(const struct pose *a, struct pose *out)
{
    struct pose r;
    glm_quat_inv((float *)a->q, r.q);
    glm_quat_rotatev(r.q, (float *)a->p, r.p);
    glm_vec3_negate(r.p);
    *out = r;
}

static void from_xr(const XrPosef *x, struct pose *out)
{
    glm_vec3_copy((vec3){x->position.x, x->position.y, x->position.z}, out->p);
    out->q[0] = x->orientation.x;
    out->q[1] = x->orientation.y;
    out->q[2] = x->orientation.z;
    out->q[3] = x->orientation.w;
}

static XrPosef to_xr(const struct pose *p)
{
    return (XrPosef){.orientation = {p->q[0], p->q[1], p->q[2], p->q[3]},
                     .position = {p->p[0], p->p[1], p->p[2]}};
}

/* A space's pose in the stage at frame K; false when it cannot be located. */
static bool space_in_stage(const struct space *s, long k, struct pose *out)
{
    struct pose base;
    if (s->reference) {
        switch (s->type) {
        case XR_REFERENCE_SPACE_TYPE_STAGE:
            glm_vec3_zero(base.p);
            glm_quat_identity(base.q);
            break;
        case XR_REFERENCE_SPACE_TYPE_LOCAL:
            glm_vec3_copy(rt.local, base.p);
            glm_quat_identity(base.q);
            break;
        case XR_REFERENCE_SPACE_TYPE_VIEW:
            head_at(k, &base);
            break;
        default:
            return false;
        }
    } else {
        int hand = -1;
        for (int h = 0; h < 2; h++) {
            XrPath p = 0;
            char name[32];
            snprintf(name, sizeof(name), "/user/hand/%s", h == 0 ? "left" : "right");
            for (int i = 0; i < rt.path_count; i++) {
                if (strcmp(rt.paths[i], name) == 0)
                    p = (XrPath)(i + 1);
            }
            if (p && p == s->subaction)
                hand = h;
        }
        if (hand < 0)
            return false;
        aim_at(k, hand, &base);
    }
    compose(&base, &s->offset, out);
    return true;
}

/* ---- paths ------------------------------------------------------------------------------ */

static XrPath intern(const char *s)
{
    for (int i = 0; i < rt.path_count; i++) {
        if (strcmp(rt.paths[i], s) == 0)
            return (XrPath)(i + 1);
    }
    if (rt.path_count == PATHS_MAX)
        return XR_NULL_PATH;
    snprintf(rt.paths[rt.path_count], XR_MAX_PATH_LENGTH, "%s", s);
    return (XrPath)++rt.path_count;
}

static const char *path_text(XrPath p)
{
    return p >= 1 && p <= (XrPath)rt.path_count ? rt.paths[p - 1] : NULL;
}

/* Each profile's input components (OpenXR 1.0, "Interaction Profile Paths"): for both hands
 * unless the name starts with "left:" or "right:". */
static const struct profile {
    const char *path;
    const char *inputs[24];
} profiles[] = {
    {"/interaction_profiles/khr/simple_controller",
     {"select/click", "menu/click", "grip/pose", "aim/pose", NULL}},
    {"/interaction_profiles/oculus/touch_controller", {"left:x/click",     "left:x/touch",
                                                       "left:y/click",     "left:y/touch",
                                                       "left:menu/click",  "right:a/click",
                                                       "right:a/touch",    "right:b/click",
                                                       "right:b/touch",    "right:system/click",
                                                       "squeeze/value",    "trigger/value",
                                                       "trigger/touch",    "thumbstick",
                                                       "thumbstick/x",     "thumbstick/y",
                                                       "thumbstick/click", "thumbstick/touch",
                                                       "thumbrest/touch",  "grip/pose",
                                                       "aim/pose",         NULL}},
    {"/interaction_profiles/valve/index_controller",
     {"system/click",   "system/touch",  "a/click",          "a/touch",
      "b/click",        "b/touch",       "squeeze/value",    "squeeze/force",
      "trigger/click",  "trigger/value", "trigger/touch",    "thumbstick",
      "thumbstick/x",   "thumbstick/y",  "thumbstick/click", "thumbstick/touch",
      "trackpad",       "trackpad/x",    "trackpad/y",       "trackpad/force",
      "trackpad/touch", "grip/pose",     "aim/pose",         NULL}},
    {"/interaction_profiles/htc/vive_controller",
     {"system/click", "squeeze/click", "menu/click", "trigger/click", "trigger/value", "trackpad",
      "trackpad/x", "trackpad/y", "trackpad/click", "trackpad/touch", "grip/pose", "aim/pose",
      NULL}},
};

/* Whether PATH is an input of PROFILE, and of which hand ("/user/hand/left/input/..."). */
static const char *profile_input(const struct profile *pr, const char *path, int *hand)
{
    const char *prefixes[2] = {"/user/hand/left/input/", "/user/hand/right/input/"};
    for (int h = 0; h < 2; h++) {
        size_t n = strlen(prefixes[h]);
        if (strncmp(path, prefixes[h], n) != 0)
            continue;
        const char *rest = path + n;
        for (int i = 0; pr->inputs[i]; i++) {
            const char *in = pr->inputs[i];
            if (strncmp(in, "left:", 5) == 0) {
                if (h != 0)
                    continue;
                in += 5;
            } else if (strncmp(in, "right:", 6) == 0) {
                if (h != 1)
                    continue;
                in += 6;
            }
            if (strcmp(in, rest) == 0) {
                *hand = h;
                return in;
            }
        }
    }
    return NULL;
}

static const struct profile *find_profile(const char *path)
{
    for (size_t i = 0; i < sizeof(profiles) / sizeof(profiles[0]); i++) {
        if (strcmp(profiles[i].path, path) == 0)
            return &profiles[i];
    }
    return NULL;
}

/* ---- events ----------------------------------------------------------------------------- */

static void enter(XrSessionState s)
{
    if (rt.queue_count == QUEUE_MAX) {
        fault("the event queue overflowed (events are not polled)");
        return;
    }
    rt.queue[(rt.queue_head + rt.queue_count++) % QUEUE_MAX] = s;
    rt.state = s;
    size_t len = strlen(rt.report.states);
    snprintf(rt.report.states + len, sizeof(rt.report.states) - len, "%s%s", len ? " " : "",
             state_name(s) + strlen("XR_SESSION_STATE_"));
}

/* The runtime wants the session to stop: back through the states to STOPPING. */
static void stop(void)
{
    if (rt.state == XR_SESSION_STATE_FOCUSED)
        enter(XR_SESSION_STATE_VISIBLE);
    if (rt.state == XR_SESSION_STATE_VISIBLE)
        enter(XR_SESSION_STATE_SYNCHRONIZED);
    if (rt.state == XR_SESSION_STATE_SYNCHRONIZED || rt.state == XR_SESSION_STATE_READY)
        enter(XR_SESSION_STATE_STOPPING);
}

/* ---- instance --------------------------------------------------------------------------- */

static const char *const extensions[] = {"XR_KHR_opengl_enable", "XR_MNDX_egl_enable"};

static XrResult enumerate_extensions(const char *layer, uint32_t cap, uint32_t *count,
                                     XrExtensionProperties *props)
{
    if (layer)
        return XR_ERROR_API_LAYER_NOT_PRESENT;
    *count = 2;
    if (cap == 0)
        return XR_SUCCESS;
    if (cap < 2)
        return XR_ERROR_SIZE_INSUFFICIENT;
    for (int i = 0; i < 2; i++) {
        snprintf(props[i].extensionName, sizeof(props[i].extensionName), "%s", extensions[i]);
        props[i].extensionVersion = 1;
    }
    return XR_SUCCESS;
}

#define INSTANCE ((XrInstance)(uintptr_t)&rt.instance_live)
#define SESSION ((XrSession)(uintptr_t)&rt.session_live)
#define ACTION_SET ((XrActionSet)(uintptr_t)&rt.action_set_live)

static XrResult create_instance(const XrInstanceCreateInfo *ci, XrInstance *out)
{
    if (rt.instance_live)
        return XR_ERROR_LIMIT_REACHED;
    load_script();
    bool gl = false;
    rt.mndx = rt.debug_utils = rt.gl_requirements = false;
    for (uint32_t i = 0; i < ci->enabledExtensionCount; i++) {
        const char *e = ci->enabledExtensionNames[i];
        if (strcmp(e, "XR_KHR_opengl_enable") == 0)
            gl = true;
        else if (strcmp(e, "XR_MNDX_egl_enable") == 0)
            rt.mndx = true;
        else
            return XR_ERROR_EXTENSION_NOT_PRESENT;
    }
    if (!gl)
        fault("an instance without XR_KHR_opengl_enable");
    rt.instance_live = true;
    rt.path_count = 0;
    rt.binding_count = 0;
    memset(rt.report.profile, 0, sizeof(rt.report.profile));
    *out = INSTANCE;
    return XR_SUCCESS;
}

static bool is_instance(XrInstance i)
{
    return rt.instance_live && i == INSTANCE;
}

static bool is_session(XrSession s)
{
    return rt.session_live && s == SESSION;
}

static void write_report(void)
{
    const char *file = getenv("ANVIL_XR_TEST_REPORT");
    if (!file)
        return;
    FILE *f = fopen(file, "w");
    if (!f)
        return;
    const struct anvil_xr_test_report *r = &rt.report;
    fprintf(f, "frames_waited %ld\nframes_ended %ld\nlayers %ld\nsyncs %ld\nfaults %d\n",
            r->frames_waited, r->frames_ended, r->layers, r->syncs, r->faults);
    fprintf(f, "binding %s\nlayer_space %s\nprofile %s\nstates %s\npose_error %g\n", r->binding,
            r->layer_space, r->profile, r->states, r->pose_error);
    for (int i = 0; i < r->faults && i < ANVIL_XR_TEST_FAULTS_KEPT; i++)
        fprintf(f, "fault %s\n", r->fault[i]);
    fclose(f);
}

static XrResult destroy_instance(XrInstance i)
{
    if (!is_instance(i))
        return XR_ERROR_HANDLE_INVALID;
    if (rt.session_live)
        fault("xrDestroyInstance with its session alive");
    rt.instance_live = false;
    write_report();
    return XR_SUCCESS;
}

static XrResult get_instance_properties(XrInstance i, XrInstanceProperties *p)
{
    if (!is_instance(i))
        return XR_ERROR_HANDLE_INVALID;
    p->runtimeVersion = XR_MAKE_VERSION(0, 1, 0);
    snprintf(p->runtimeName, sizeof(p->runtimeName), "anvil test runtime");
    return XR_SUCCESS;
}

static XrResult result_to_string(XrInstance i, XrResult r, char out[XR_MAX_RESULT_STRING_SIZE])
{
    const char *name = result_name(r);
    if (name)
        snprintf(out, XR_MAX_RESULT_STRING_SIZE, "%s", name);
    else
        snprintf(out, XR_MAX_RESULT_STRING_SIZE, "XR_UNKNOWN_%d", (int)r);
    return XR_SUCCESS;
}

static XrResult structure_to_string(XrInstance i, XrStructureType t,
                                    char out[XR_MAX_STRUCTURE_NAME_SIZE])
{
    const char *name = type_name(t);
    if (name)
        snprintf(out, XR_MAX_STRUCTURE_NAME_SIZE, "%s", name);
    else
        snprintf(out, XR_MAX_STRUCTURE_NAME_SIZE, "XR_UNKNOWN_STRUCTURE_TYPE_%d", (int)t);
    return XR_SUCCESS;
}

static XrResult string_to_path(XrInstance i, const char *s, XrPath *out)
{
    if (!is_instance(i))
        return XR_ERROR_HANDLE_INVALID;
    if (s[0] != '/' || strlen(s) >= XR_MAX_PATH_LENGTH || s[strlen(s) - 1] == '/')
        return XR_ERROR_PATH_FORMAT_INVALID;
    for (const char *c = s; *c; c++) {
        if (!((*c >= 'a' && *c <= 'z') || (*c >= '0' && *c <= '9') || *c == '/' || *c == '_' ||
              *c == '-' || *c == '.'))
            return XR_ERROR_PATH_FORMAT_INVALID;
    }
    *out = intern(s);
    return *out ? XR_SUCCESS : XR_ERROR_PATH_COUNT_EXCEEDED;
}

static XrResult path_to_string(XrInstance i, XrPath p, uint32_t cap, uint32_t *count, char *out)
{
    const char *s = path_text(p);
    if (!is_instance(i))
        return XR_ERROR_HANDLE_INVALID;
    if (!s)
        return XR_ERROR_PATH_INVALID;
    *count = (uint32_t)strlen(s) + 1;
    if (cap == 0)
        return XR_SUCCESS;
    if (cap < *count)
        return XR_ERROR_SIZE_INSUFFICIENT;
    memcpy(out, s, *count);
    return XR_SUCCESS;
}

/* ---- system ----------------------------------------------------------------------------- */

#define SYSTEM_ID 7

static XrResult get_system(XrInstance i, const XrSystemGetInfo *gi, XrSystemId *out)
{
    if (!is_instance(i))
        return XR_ERROR_HANDLE_INVALID;
    if (gi->formFactor != XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY)
        return XR_ERROR_FORM_FACTOR_UNSUPPORTED;
    *out = SYSTEM_ID;
    return XR_SUCCESS;
}

static XrResult get_system_properties(XrInstance i, XrSystemId s, XrSystemProperties *p)
{
    if (!is_instance(i) || s != SYSTEM_ID)
        return XR_ERROR_SYSTEM_INVALID;
    p->systemId = s;
    p->vendorId = 0;
    snprintf(p->systemName, sizeof(p->systemName), "scripted headset");
    p->graphicsProperties.maxSwapchainImageWidth = 4096;
    p->graphicsProperties.maxSwapchainImageHeight = 4096;
    p->graphicsProperties.maxLayerCount = 16;
    p->trackingProperties.orientationTracking = XR_TRUE;
    p->trackingProperties.positionTracking = XR_TRUE;
    return XR_SUCCESS;
}

static XrResult enumerate_view_configurations(XrInstance i, XrSystemId s, uint32_t cap,
                                              uint32_t *count, XrViewConfigurationType *out)
{
    if (!is_instance(i) || s != SYSTEM_ID)
        return XR_ERROR_SYSTEM_INVALID;
    *count = 1;
    if (cap == 0)
        return XR_SUCCESS;
    out[0] = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
    return XR_SUCCESS;
}

static XrResult get_view_configuration_properties(XrInstance i, XrSystemId s,
                                                  XrViewConfigurationType t,
                                                  XrViewConfigurationProperties *p)
{
    if (!is_instance(i) || s != SYSTEM_ID)
        return XR_ERROR_SYSTEM_INVALID;
    if (t != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO)
        return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
    p->viewConfigurationType = t;
    p->fovMutable = XR_FALSE;
    return XR_SUCCESS;
}

static XrResult enumerate_view_configuration_views(XrInstance i, XrSystemId s,
                                                   XrViewConfigurationType t, uint32_t cap,
                                                   uint32_t *count, XrViewConfigurationView *views)
{
    if (!is_instance(i) || s != SYSTEM_ID)
        return XR_ERROR_SYSTEM_INVALID;
    if (t != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO)
        return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
    *count = 2;
    if (cap == 0)
        return XR_SUCCESS;
    if (cap < 2)
        return XR_ERROR_SIZE_INSUFFICIENT;
    for (int e = 0; e < 2; e++) {
        views[e].recommendedImageRectWidth = (uint32_t)rt.size[0];
        views[e].recommendedImageRectHeight = (uint32_t)rt.size[1];
        views[e].maxImageRectWidth = 4096;
        views[e].maxImageRectHeight = 4096;
        views[e].recommendedSwapchainSampleCount = 1;
        views[e].maxSwapchainSampleCount = 1;
    }
    return XR_SUCCESS;
}

static XrResult enumerate_blend_modes(XrInstance i, XrSystemId s, XrViewConfigurationType t,
                                      uint32_t cap, uint32_t *count, XrEnvironmentBlendMode *out)
{
    if (!is_instance(i) || s != SYSTEM_ID)
        return XR_ERROR_SYSTEM_INVALID;
    *count = 1;
    if (cap == 0)
        return XR_SUCCESS;
    out[0] = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
    return XR_SUCCESS;
}

static XrResult gl_requirements(XrInstance i, XrSystemId s, XrGraphicsRequirementsOpenGLKHR *r)
{
    if (!is_instance(i) || s != SYSTEM_ID)
        return XR_ERROR_SYSTEM_INVALID;
    r->minApiVersionSupported = XR_MAKE_VERSION(4, 3, 0);
    r->maxApiVersionSupported = XR_MAKE_VERSION(4, 6, 0);
    rt.gl_requirements = true;
    return XR_SUCCESS;
}

/* ---- session ---------------------------------------------------------------------------- */

/* Makes the application's context current if it is not (a runtime may, XR_KHR_opengl_enable
 * "threading"); false when it cannot. */
static bool app_context(void)
{
    if (rt.egl) {
        if (eglGetCurrentContext() == rt.egl_context)
            return true;
        return eglMakeCurrent(rt.egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, rt.egl_context);
    }
    if (glXGetCurrentContext() == rt.glx_context)
        return true;
    return glXMakeCurrent(rt.x_display, rt.glx_drawable, rt.glx_context);
}

static XrResult create_session(XrInstance i, const XrSessionCreateInfo *ci, XrSession *out)
{
    if (!is_instance(i))
        return XR_ERROR_HANDLE_INVALID;
    if (ci->systemId != SYSTEM_ID)
        return XR_ERROR_SYSTEM_INVALID;
    if (rt.session_live)
        return XR_ERROR_LIMIT_REACHED;
    if (!rt.gl_requirements)
        return XR_ERROR_GRAPHICS_REQUIREMENTS_CALL_MISSING;
    int found = 0;
    for (const XrBaseInStructure *b = ci->next; b; b = b->next) {
        if (b->type == XR_TYPE_GRAPHICS_BINDING_EGL_MNDX) {
            if (!rt.mndx)
                return XR_ERROR_VALIDATION_FAILURE;
            const XrGraphicsBindingEGLMNDX *e = (const void *)b;
            rt.egl = true;
            rt.egl_display = e->display;
            rt.egl_context = e->context;
            if (!e->getProcAddress || !e->display || !e->context)
                return XR_ERROR_VALIDATION_FAILURE;
            found++;
        } else if (b->type == XR_TYPE_GRAPHICS_BINDING_OPENGL_XLIB_KHR) {
            const XrGraphicsBindingOpenGLXlibKHR *x = (const void *)b;
            rt.egl = false;
            rt.x_display = x->xDisplay;
            rt.glx_drawable = x->glxDrawable;
            rt.glx_context = x->glxContext;
            if (!x->xDisplay || !x->glxContext || !x->glxDrawable || !x->glxFBConfig ||
                !x->visualid)
                return XR_ERROR_VALIDATION_FAILURE;
            found++;
        }
    }
    if (found != 1)
        return XR_ERROR_GRAPHICS_DEVICE_INVALID;
    bool current = rt.egl ? eglGetCurrentContext() == rt.egl_context
                          : glXGetCurrentContext() == rt.glx_context;
    if (!current)
        fault("xrCreateSession: the application's context is not current");
    snprintf(rt.report.binding, sizeof(rt.report.binding), "%s", rt.egl ? "egl" : "xlib");
    rt.session_live = true;
    rt.running = rt.exit_requested = rt.lost = false;
    rt.queue_head = rt.queue_count = 0;
    rt.waited = rt.begun = false;
    rt.attached = false;
    rt.report.states[0] = '\0';
    enter(XR_SESSION_STATE_IDLE);
    enter(XR_SESSION_STATE_READY);
    *out = SESSION;
    return XR_SUCCESS;
}

static XrResult destroy_session(XrSession s)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    for (int i = 0; i < 4; i++) {
        if (rt.swapchains[i].live)
            fault("xrDestroySession with a swapchain alive");
    }
    rt.session_live = false;
    for (int i = 0; i < SPACES_MAX; i++)
        rt.spaces[i].live = false;
    return XR_SUCCESS;
}

static XrResult begin_session(XrSession s, const XrSessionBeginInfo *bi)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    if (rt.lost)
        return XR_ERROR_SESSION_LOST;
    if (rt.running)
        return XR_ERROR_SESSION_RUNNING;
    if (rt.state != XR_SESSION_STATE_READY) {
        fault("xrBeginSession in state %s", state_name(rt.state));
        return XR_ERROR_SESSION_NOT_READY;
    }
    if (bi->primaryViewConfigurationType != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO)
        return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
    rt.running = true;
    return XR_SUCCESS;
}

static XrResult end_session(XrSession s)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    if (rt.lost)
        return XR_ERROR_SESSION_LOST;
    if (!rt.running)
        return XR_ERROR_SESSION_NOT_RUNNING;
    if (rt.state != XR_SESSION_STATE_STOPPING) {
        fault("xrEndSession in state %s", state_name(rt.state));
        return XR_ERROR_SESSION_NOT_STOPPING;
    }
    if (rt.begun)
        fault("xrEndSession inside a frame (xrBeginFrame without xrEndFrame)");
    rt.running = false;
    rt.waited = rt.begun = false;
    enter(XR_SESSION_STATE_IDLE);
    if (rt.exit_requested)
        enter(XR_SESSION_STATE_EXITING);
    return XR_SUCCESS;
}

static XrResult request_exit(XrSession s)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    if (rt.lost)
        return XR_ERROR_SESSION_LOST;
    if (!rt.running)
        return XR_ERROR_SESSION_NOT_RUNNING;
    rt.exit_requested = true;
    stop();
    return XR_SUCCESS;
}

static XrResult poll_event(XrInstance i, XrEventDataBuffer *ev)
{
    if (!is_instance(i))
        return XR_ERROR_HANDLE_INVALID;
    if (rt.profile_event) {
        rt.profile_event = false;
        XrEventDataInteractionProfileChanged *p = (void *)ev;
        *p = (XrEventDataInteractionProfileChanged){
            .type = XR_TYPE_EVENT_DATA_INTERACTION_PROFILE_CHANGED, .session = SESSION};
        return XR_SUCCESS;
    }
    if (rt.queue_count == 0)
        return XR_EVENT_UNAVAILABLE;
    XrSessionState s = rt.queue[rt.queue_head];
    rt.queue_head = (rt.queue_head + 1) % QUEUE_MAX;
    rt.queue_count--;
    XrEventDataSessionStateChanged *e = (void *)ev;
    *e = (XrEventDataSessionStateChanged){.type = XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED,
                                          .session = SESSION,
                                          .state = s,
                                          .time = rt.frame_time};
    return XR_SUCCESS;
}

/* ---- spaces ----------------------------------------------------------------------------- */

static XrSpace space_handle(int i)
{
    return (XrSpace)(uintptr_t)&rt.spaces[i];
}

static struct space *space_of(XrSpace h)
{
    for (int i = 0; i < SPACES_MAX; i++) {
        if (rt.spaces[i].live && space_handle(i) == h)
            return &rt.spaces[i];
    }
    return NULL;
}

static XrResult new_space(struct space *s, XrSpace *out)
{
    for (int i = 0; i < SPACES_MAX; i++) {
        if (!rt.spaces[i].live) {
            rt.spaces[i] = *s;
            rt.spaces[i].live = true;
            *out = space_handle(i);
            return XR_SUCCESS;
        }
    }
    return XR_ERROR_LIMIT_REACHED;
}

static bool pose_valid(const XrPosef *p)
{
    float n = sqrtf(p->orientation.x * p->orientation.x + p->orientation.y * p->orientation.y +
                    p->orientation.z * p->orientation.z + p->orientation.w * p->orientation.w);
    return fabsf(n - 1.0f) < 1e-3f && isfinite(p->position.x) && isfinite(p->position.y) &&
           isfinite(p->position.z);
}

static XrResult enumerate_reference_spaces(XrSession s, uint32_t cap, uint32_t *count,
                                           XrReferenceSpaceType *out)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    XrReferenceSpaceType all[3] = {XR_REFERENCE_SPACE_TYPE_VIEW, XR_REFERENCE_SPACE_TYPE_LOCAL,
                                   XR_REFERENCE_SPACE_TYPE_STAGE};
    *count = rt.stage ? 3 : 2;
    if (cap == 0)
        return XR_SUCCESS;
    if (cap < *count)
        return XR_ERROR_SIZE_INSUFFICIENT;
    memcpy(out, all, sizeof(all[0]) * *count);
    return XR_SUCCESS;
}

static XrResult create_reference_space(XrSession s, const XrReferenceSpaceCreateInfo *ci,
                                       XrSpace *out)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    if (ci->referenceSpaceType != XR_REFERENCE_SPACE_TYPE_VIEW &&
        ci->referenceSpaceType != XR_REFERENCE_SPACE_TYPE_LOCAL &&
        (ci->referenceSpaceType != XR_REFERENCE_SPACE_TYPE_STAGE || !rt.stage))
        return XR_ERROR_REFERENCE_SPACE_UNSUPPORTED;
    if (!pose_valid(&ci->poseInReferenceSpace))
        return XR_ERROR_POSE_INVALID;
    struct space sp = {.reference = true, .type = ci->referenceSpaceType};
    from_xr(&ci->poseInReferenceSpace, &sp.offset);
    return new_space(&sp, out);
}

static XrResult get_bounds(XrSession s, XrReferenceSpaceType t, XrExtent2Df *out)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    if (t == XR_REFERENCE_SPACE_TYPE_STAGE && rt.stage) {
        *out = (XrExtent2Df){3.0f, 3.0f};
        return XR_SUCCESS;
    }
    *out = (XrExtent2Df){0.0f, 0.0f};
    return XR_SPACE_BOUNDS_UNAVAILABLE;
}

static struct action *action_of(XrAction a)
{
    for (int i = 0; i < ACTIONS_MAX; i++) {
        if (rt.actions[i].live && (XrAction)(uintptr_t)&rt.actions[i] == a)
            return &rt.actions[i];
    }
    return NULL;
}

static XrResult create_action_space(XrSession s, const XrActionSpaceCreateInfo *ci, XrSpace *out)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    struct action *a = action_of(ci->action);
    if (!a)
        return XR_ERROR_HANDLE_INVALID;
    if (a->type != XR_ACTION_TYPE_POSE_INPUT)
        return XR_ERROR_ACTION_TYPE_MISMATCH;
    bool sub = ci->subactionPath == XR_NULL_PATH;
    for (int i = 0; i < a->subactions; i++)
        sub = sub || a->subaction[i] == ci->subactionPath;
    if (!sub)
        return XR_ERROR_PATH_UNSUPPORTED;
    if (!pose_valid(&ci->poseInActionSpace))
        return XR_ERROR_POSE_INVALID;
    struct space sp = {.reference = false, .action = a, .subaction = ci->subactionPath};
    from_xr(&ci->poseInActionSpace, &sp.offset);
    return new_space(&sp, out);
}

static XrResult destroy_space(XrSpace h)
{
    struct space *s = space_of(h);
    if (!s)
        return XR_ERROR_HANDLE_INVALID;
    s->live = false;
    return XR_SUCCESS;
}

/* Whether action A is bound, in the current profile, to an input of HAND (-1: either). */
static bool bound(const struct action *a, int hand, const char *component_end);

static XrResult locate_space(XrSpace sh, XrSpace bh, XrTime t, XrSpaceLocation *loc)
{
    struct space *s = space_of(sh), *b = space_of(bh);
    if (!s || !b)
        return XR_ERROR_HANDLE_INVALID;
    if (t <= 0)
        return XR_ERROR_TIME_INVALID;
    long k = frame_of(t);
    struct pose ps, pb, inv, rel;
    bool tracked = s->reference || (rt.synced && bound(s->action, -1, "/pose"));
    if (!tracked || !space_in_stage(s, k, &ps) || !space_in_stage(b, k, &pb)) {
        loc->locationFlags = 0;
        loc->pose = (XrPosef){.orientation = {0, 0, 0, 1}};
        return XR_SUCCESS;
    }
    invert(&pb, &inv);
    compose(&inv, &ps, &rel);
    loc->pose = to_xr(&rel);
    loc->locationFlags =
        XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_POSITION_VALID_BIT |
        XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT | XR_SPACE_LOCATION_POSITION_TRACKED_BIT;
    if (s->reference && s->type == XR_REFERENCE_SPACE_TYPE_VIEW) {
        const float v[7] = {rel.p[0], rel.p[1], rel.p[2], rel.q[0], rel.q[1], rel.q[2], rel.q[3]};
        memcpy(rt.report.located_head, v, sizeof(v));
    }
    return XR_SUCCESS;
}

/* Eye E's pose in the stage at frame K. */
static void eye_in_stage(int e, long k, struct pose *out)
{
    struct pose head, eye = {.q = {0, 0, 0, 1}};
    head_at(k, &head);
    glm_vec3_copy(rt.eye[e], eye.p);
    compose(&head, &eye, out);
}

static XrResult locate_views(XrSession s, const XrViewLocateInfo *li, XrViewState *vs, uint32_t cap,
                             uint32_t *count, XrView *views)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    if (li->viewConfigurationType != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO)
        return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
    struct space *sp = space_of(li->space);
    if (!sp)
        return XR_ERROR_HANDLE_INVALID;
    if (li->displayTime <= 0)
        return XR_ERROR_TIME_INVALID;
    *count = 2;
    if (cap == 0)
        return XR_SUCCESS;
    if (cap < 2)
        return XR_ERROR_SIZE_INSUFFICIENT;
    long k = frame_of(li->displayTime);
    struct pose base, inv;
    space_in_stage(sp, k, &base);
    invert(&base, &inv);
    for (int e = 0; e < 2; e++) {
        struct pose eye, rel;
        eye_in_stage(e, k, &eye);
        compose(&inv, &eye, &rel);
        views[e].pose = to_xr(&rel);
        views[e].fov = (XrFovf){glm_rad(rt.fov_deg[e][0]), glm_rad(rt.fov_deg[e][1]),
                                glm_rad(rt.fov_deg[e][2]), glm_rad(rt.fov_deg[e][3])};
    }
    vs->viewStateFlags = XR_VIEW_STATE_ORIENTATION_VALID_BIT | XR_VIEW_STATE_POSITION_VALID_BIT |
                         XR_VIEW_STATE_ORIENTATION_TRACKED_BIT | XR_VIEW_STATE_POSITION_TRACKED_BIT;
    return XR_SUCCESS;
}

/* ---- swapchains ------------------------------------------------------------------------- */

static const int64_t formats[] = {GL_SRGB8_ALPHA8, GL_RGBA8, GL_RGBA16F};

static XrResult enumerate_swapchain_formats(XrSession s, uint32_t cap, uint32_t *count,
                                            int64_t *out)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    *count = 3;
    if (cap == 0)
        return XR_SUCCESS;
    if (cap < 3)
        return XR_ERROR_SIZE_INSUFFICIENT;
    memcpy(out, formats, sizeof(formats));
    return XR_SUCCESS;
}

static struct swapchain *swapchain_of(XrSwapchain h)
{
    for (int i = 0; i < 4; i++) {
        if (rt.swapchains[i].live && (XrSwapchain)(uintptr_t)&rt.swapchains[i] == h)
            return &rt.swapchains[i];
    }
    return NULL;
}

static XrResult create_swapchain(XrSession s, const XrSwapchainCreateInfo *ci, XrSwapchain *out)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    bool known = false;
    for (int i = 0; i < 3; i++)
        known = known || formats[i] == ci->format;
    if (!known)
        return XR_ERROR_SWAPCHAIN_FORMAT_UNSUPPORTED;
    if (ci->sampleCount != 1 || ci->faceCount != 1 || ci->arraySize != 1 || ci->mipCount != 1 ||
        ci->width < 1 || ci->height < 1 || ci->width > 4096 || ci->height > 4096)
        return XR_ERROR_VALIDATION_FAILURE;
    if (!(ci->usageFlags &
          (XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT | XR_SWAPCHAIN_USAGE_TRANSFER_DST_BIT |
           XR_SWAPCHAIN_USAGE_UNORDERED_ACCESS_BIT)))
        fault("xrCreateSwapchain: no usage flag lets the application write the images");
    struct swapchain *sc = NULL;
    for (int i = 0; i < 4 && !sc; i++) {
        if (!rt.swapchains[i].live)
            sc = &rt.swapchains[i];
    }
    if (!sc)
        return XR_ERROR_LIMIT_REACHED;
    if (!app_context()) {
        fault("xrCreateSwapchain: the application's context cannot be made current");
        return XR_ERROR_GRAPHICS_DEVICE_INVALID;
    }
    memset(sc, 0, sizeof(*sc));
    sc->format = ci->format;
    sc->width = (int)ci->width;
    sc->height = (int)ci->height;
    glCreateTextures(GL_TEXTURE_2D, IMAGES, sc->tex);
    for (int i = 0; i < IMAGES; i++)
        glTextureStorage2D(sc->tex[i], 1, (GLenum)ci->format, sc->width, sc->height);
    sc->acquired = sc->waited = sc->released = -1;
    sc->live = true;
    *out = (XrSwapchain)(uintptr_t)sc;
    return XR_SUCCESS;
}

static XrResult destroy_swapchain(XrSwapchain h)
{
    struct swapchain *sc = swapchain_of(h);
    if (!sc)
        return XR_ERROR_HANDLE_INVALID;
    if (app_context())
        glDeleteTextures(IMAGES, sc->tex);
    else
        fault("xrDestroySwapchain: the application's context cannot be made current");
    sc->live = false;
    return XR_SUCCESS;
}

static XrResult enumerate_swapchain_images(XrSwapchain h, uint32_t cap, uint32_t *count,
                                           XrSwapchainImageBaseHeader *images)
{
    struct swapchain *sc = swapchain_of(h);
    if (!sc)
        return XR_ERROR_HANDLE_INVALID;
    *count = IMAGES;
    if (cap == 0)
        return XR_SUCCESS;
    if (cap < IMAGES)
        return XR_ERROR_SIZE_INSUFFICIENT;
    XrSwapchainImageOpenGLKHR *gl = (XrSwapchainImageOpenGLKHR *)images;
    for (int i = 0; i < IMAGES; i++) {
        if (gl[i].type != XR_TYPE_SWAPCHAIN_IMAGE_OPENGL_KHR)
            return XR_ERROR_VALIDATION_FAILURE;
        gl[i].image = sc->tex[i];
    }
    return XR_SUCCESS;
}

static XrResult acquire_image(XrSwapchain h, const XrSwapchainImageAcquireInfo *ai, uint32_t *index)
{
    struct swapchain *sc = swapchain_of(h);
    if (!sc)
        return XR_ERROR_HANDLE_INVALID;
    if (sc->acquired >= 0) {
        fault("xrAcquireSwapchainImage with an image still acquired");
        return XR_ERROR_CALL_ORDER_INVALID;
    }
    sc->acquired = sc->next;
    sc->next = (sc->next + 1) % IMAGES;
    *index = (uint32_t)sc->acquired;
    return XR_SUCCESS;
}

static XrResult wait_image(XrSwapchain h, const XrSwapchainImageWaitInfo *wi)
{
    struct swapchain *sc = swapchain_of(h);
    if (!sc)
        return XR_ERROR_HANDLE_INVALID;
    if (sc->acquired < 0 || sc->waited >= 0) {
        fault("xrWaitSwapchainImage without an acquired image to wait for");
        return XR_ERROR_CALL_ORDER_INVALID;
    }
    sc->waited = sc->acquired;
    return XR_SUCCESS;
}

static XrResult release_image(XrSwapchain h, const XrSwapchainImageReleaseInfo *ri)
{
    struct swapchain *sc = swapchain_of(h);
    if (!sc)
        return XR_ERROR_HANDLE_INVALID;
    if (sc->waited < 0) {
        fault("xrReleaseSwapchainImage without a waited image");
        return XR_ERROR_CALL_ORDER_INVALID;
    }
    sc->released = sc->waited;
    sc->released_since_frame = true;
    sc->acquired = sc->waited = -1;
    return XR_SUCCESS;
}

/* ---- frames ----------------------------------------------------------------------------- */

static void fire_events(long k)
{
    for (int i = 0; i < rt.event_count; i++) {
        struct script_event *e = &rt.events[i];
        if (e->fired || e->frame > k)
            continue;
        if (e->kind == EV_EXIT) {
            e->fired = true;
            rt.exit_requested = true;
            stop();
        } else if (e->kind == EV_LOSE) {
            e->fired = true;
            enter(XR_SESSION_STATE_LOSS_PENDING);
            rt.lost = true;
        }
    }
}

static XrResult wait_frame(XrSession s, const XrFrameWaitInfo *wi, XrFrameState *fs)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    if (rt.lost)
        return XR_ERROR_SESSION_LOST;
    if (!rt.running)
        return XR_ERROR_SESSION_NOT_RUNNING;
    if (rt.waited)
        fault("xrWaitFrame twice without xrBeginFrame between");
    long k = rt.waits++;
    rt.report.frames_waited++;
    rt.frame_time = TIME0_NS + (XrTime)(k + 1) * PERIOD_NS;
    rt.waited = true;
    if (rt.state == XR_SESSION_STATE_READY) {
        /* The first frame synchronises; the next ones are shown and focused. */
        enter(XR_SESSION_STATE_SYNCHRONIZED);
    } else if (rt.state == XR_SESSION_STATE_SYNCHRONIZED && !rt.exit_requested) {
        enter(XR_SESSION_STATE_VISIBLE);
        enter(XR_SESSION_STATE_FOCUSED);
    }
    fire_events(k);
    fs->predictedDisplayTime = rt.frame_time;
    fs->predictedDisplayPeriod = PERIOD_NS;
    fs->shouldRender = rt.state == XR_SESSION_STATE_VISIBLE || rt.state == XR_SESSION_STATE_FOCUSED;
    return XR_SUCCESS;
}

static XrResult begin_frame(XrSession s, const XrFrameBeginInfo *bi)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    if (rt.lost)
        return XR_ERROR_SESSION_LOST;
    if (!rt.running)
        return XR_ERROR_SESSION_NOT_RUNNING;
    if (!rt.waited) {
        fault("xrBeginFrame without xrWaitFrame");
        return XR_ERROR_CALL_ORDER_INVALID;
    }
    rt.waited = false;
    rt.report.frames_begun++;
    bool discarded = rt.begun;
    rt.begun = true;
    for (int i = 0; i < 4; i++)
        rt.swapchains[i].released_since_frame = false;
    return discarded ? XR_FRAME_DISCARDED : XR_SUCCESS;
}

static void keep_image(int eye, const struct swapchain *sc, const XrRect2Di *rect)
{
    size_t bytes = (size_t)rect->extent.width * (size_t)rect->extent.height * 4;
    uint8_t *whole = malloc((size_t)sc->width * (size_t)sc->height * 4);
    uint8_t *img = realloc(rt.image[eye], bytes);
    if (!whole || !img) {
        free(whole);
        fault("out of memory for a submitted image");
        return;
    }
    rt.image[eye] = img;
    if (!app_context()) {
        free(whole);
        fault("xrEndFrame: the application's context cannot be made current");
        return;
    }
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glGetTextureImage(sc->tex[sc->released], 0, GL_RGBA, GL_UNSIGNED_BYTE,
                      (GLsizei)((size_t)sc->width * sc->height * 4), whole);
    for (int y = 0; y < rect->extent.height; y++)
        memcpy(img + (size_t)y * rect->extent.width * 4,
               whole + ((size_t)(y + rect->offset.y) * sc->width + rect->offset.x) * 4,
               (size_t)rect->extent.width * 4);
    free(whole);
    rt.image_size[eye][0] = rect->extent.width;
    rt.image_size[eye][1] = rect->extent.height;
}

static const char *space_name(const struct space *s)
{
    if (!s->reference)
        return "action";
    return s->type == XR_REFERENCE_SPACE_TYPE_STAGE   ? "stage"
           : s->type == XR_REFERENCE_SPACE_TYPE_LOCAL ? "local"
                                                      : "view";
}

static XrResult check_layer(const XrCompositionLayerBaseHeader *h, XrTime time)
{
    if (!h || h->type != XR_TYPE_COMPOSITION_LAYER_PROJECTION) {
        fault("xrEndFrame: a layer that is not a projection layer");
        return XR_ERROR_LAYER_INVALID;
    }
    const XrCompositionLayerProjection *p = (const void *)h;
    struct space *sp = space_of(p->space);
    if (!sp) {
        fault("xrEndFrame: the layer's space is not a live space");
        return XR_ERROR_HANDLE_INVALID;
    }
    if (p->viewCount != 2) {
        fault("xrEndFrame: a projection layer of %u views", p->viewCount);
        return XR_ERROR_VALIDATION_FAILURE;
    }
    long k = frame_of(time);
    struct pose base, inv;
    space_in_stage(sp, k, &base);
    invert(&base, &inv);
    for (int e = 0; e < 2; e++) {
        const XrCompositionLayerProjectionView *v = &p->views[e];
        if (!pose_valid(&v->pose)) {
            fault("xrEndFrame: view %d's pose is not a unit rotation and finite position", e);
            return XR_ERROR_POSE_INVALID;
        }
        if (!(v->fov.angleLeft < v->fov.angleRight && v->fov.angleDown < v->fov.angleUp)) {
            fault("xrEndFrame: view %d's field of view is empty", e);
            return XR_ERROR_VALIDATION_FAILURE;
        }
        struct swapchain *sc = swapchain_of(v->subImage.swapchain);
        if (!sc) {
            fault("xrEndFrame: view %d's swapchain is not a live swapchain", e);
            return XR_ERROR_HANDLE_INVALID;
        }
        const XrRect2Di *r = &v->subImage.imageRect;
        if (r->offset.x < 0 || r->offset.y < 0 || r->extent.width < 1 || r->extent.height < 1 ||
            r->offset.x + r->extent.width > sc->width ||
            r->offset.y + r->extent.height > sc->height) {
            fault("xrEndFrame: view %d's image rectangle lies outside its swapchain", e);
            return XR_ERROR_SWAPCHAIN_RECT_INVALID;
        }
        if (v->subImage.imageArrayIndex != 0) {
            fault("xrEndFrame: view %d's image array index %u", e, v->subImage.imageArrayIndex);
            return XR_ERROR_VALIDATION_FAILURE;
        }
        if (sc->released < 0 || !sc->released_since_frame) {
            fault("xrEndFrame: view %d's swapchain has no image released in this frame", e);
            return XR_ERROR_LAYER_INVALID;
        }
        /* How far the submitted eye is from where the runtime put it. */
        struct pose eye, rel;
        eye_in_stage(e, k, &eye);
        compose(&inv, &eye, &rel);
        float d = glm_vec3_distance(
            rel.p, (vec3){v->pose.position.x, v->pose.position.y, v->pose.position.z});
        if (d > rt.report.pose_error)
            rt.report.pose_error = d;
        const float pose[7] = {v->pose.position.x,    v->pose.position.y,    v->pose.position.z,
                               v->pose.orientation.x, v->pose.orientation.y, v->pose.orientation.z,
                               v->pose.orientation.w};
        memcpy(rt.report.layer_pose[e], pose, sizeof(pose));
        const float fov[4] = {v->fov.angleLeft, v->fov.angleRight, v->fov.angleUp,
                              v->fov.angleDown};
        memcpy(rt.report.layer_fov[e], fov, sizeof(fov));
        keep_image(e, sc, r);
    }
    snprintf(rt.report.layer_space, sizeof(rt.report.layer_space), "%s", space_name(sp));
    return XR_SUCCESS;
}

static XrResult end_frame(XrSession s, const XrFrameEndInfo *ei)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    if (rt.lost)
        return XR_ERROR_SESSION_LOST;
    if (!rt.running)
        return XR_ERROR_SESSION_NOT_RUNNING;
    if (!rt.begun) {
        fault("xrEndFrame without xrBeginFrame");
        return XR_ERROR_CALL_ORDER_INVALID;
    }
    rt.begun = false;
    rt.report.frames_ended++;
    if (ei->displayTime != rt.frame_time)
        fault("xrEndFrame: display time %lld is not the predicted %lld", (long long)ei->displayTime,
              (long long)rt.frame_time);
    if (ei->environmentBlendMode != XR_ENVIRONMENT_BLEND_MODE_OPAQUE) {
        fault("xrEndFrame: blend mode %d", (int)ei->environmentBlendMode);
        return XR_ERROR_ENVIRONMENT_BLEND_MODE_UNSUPPORTED;
    }
    if (ei->layerCount > 1)
        fault("xrEndFrame: %u layers (anvil submits one)", ei->layerCount);
    for (uint32_t i = 0; i < ei->layerCount; i++) {
        XrResult r = check_layer(ei->layers[i], ei->displayTime);
        if (r != XR_SUCCESS)
            return r;
        rt.report.layers++;
    }
    return XR_SUCCESS;
}

/* ---- actions ---------------------------------------------------------------------------- */

static XrResult create_action_set(XrInstance i, const XrActionSetCreateInfo *ci, XrActionSet *out)
{
    if (!is_instance(i))
        return XR_ERROR_HANDLE_INVALID;
    if (rt.action_set_live)
        return XR_ERROR_LIMIT_REACHED;
    rt.action_set_live = true;
    memset(rt.actions, 0, sizeof(rt.actions));
    *out = ACTION_SET;
    return XR_SUCCESS;
}

static XrResult destroy_action_set(XrActionSet h)
{
    if (!rt.action_set_live || h != ACTION_SET)
        return XR_ERROR_HANDLE_INVALID;
    rt.action_set_live = false;
    memset(rt.actions, 0, sizeof(rt.actions));
    return XR_SUCCESS;
}

static XrResult create_action(XrActionSet set, const XrActionCreateInfo *ci, XrAction *out)
{
    if (!rt.action_set_live || set != ACTION_SET)
        return XR_ERROR_HANDLE_INVALID;
    if (rt.attached)
        return XR_ERROR_ACTIONSETS_ALREADY_ATTACHED;
    if (ci->countSubactionPaths > 4)
        return XR_ERROR_PATH_UNSUPPORTED;
    for (int i = 0; i < ACTIONS_MAX; i++) {
        struct action *a = &rt.actions[i];
        if (a->live) {
            if (strcmp(a->name, ci->actionName) == 0)
                return XR_ERROR_NAME_DUPLICATED;
            continue;
        }
        a->live = true;
        a->type = ci->actionType;
        snprintf(a->name, sizeof(a->name), "%s", ci->actionName);
        a->subactions = (int)ci->countSubactionPaths;
        for (uint32_t s = 0; s < ci->countSubactionPaths; s++) {
            const char *p = path_text(ci->subactionPaths[s]);
            if (!p || strncmp(p, "/user/hand/", 11) != 0)
                return XR_ERROR_PATH_UNSUPPORTED;
            a->subaction[s] = ci->subactionPaths[s];
        }
        *out = (XrAction)(uintptr_t)a;
        return XR_SUCCESS;
    }
    return XR_ERROR_LIMIT_REACHED;
}

static XrResult destroy_action(XrAction h)
{
    struct action *a = action_of(h);
    if (!a)
        return XR_ERROR_HANDLE_INVALID;
    a->live = false;
    return XR_SUCCESS;
}

static bool ends_with(const char *s, const char *end)
{
    size_t n = strlen(s), m = strlen(end);
    return n >= m && strcmp(s + n - m, end) == 0;
}

/* Whether an input component can drive an action of type T. */
static bool type_fits(XrActionType t, const char *component)
{
    bool pose = ends_with(component, "/pose");
    bool vec = strcmp(component, "thumbstick") == 0 || strcmp(component, "trackpad") == 0;
    switch (t) {
    case XR_ACTION_TYPE_POSE_INPUT:
        return pose;
    case XR_ACTION_TYPE_VECTOR2F_INPUT:
        return vec;
    case XR_ACTION_TYPE_BOOLEAN_INPUT:
    case XR_ACTION_TYPE_FLOAT_INPUT:
        return !pose && !vec;
    default:
        return false;
    }
}

static XrResult suggest_bindings(XrInstance i, const XrInteractionProfileSuggestedBinding *sb)
{
    if (!is_instance(i))
        return XR_ERROR_HANDLE_INVALID;
    if (rt.attached)
        return XR_ERROR_ACTIONSETS_ALREADY_ATTACHED;
    const char *profile = path_text(sb->interactionProfile);
    const struct profile *pr = profile ? find_profile(profile) : NULL;
    if (!pr)
        return XR_ERROR_PATH_UNSUPPORTED;
    /* A new suggestion for a profile replaces the old one. */
    int kept = 0;
    for (int b = 0; b < rt.binding_count; b++) {
        if (rt.bindings[b].profile != sb->interactionProfile)
            rt.bindings[kept++] = rt.bindings[b];
    }
    rt.binding_count = kept;
    for (uint32_t b = 0; b < sb->countSuggestedBindings; b++) {
        const XrActionSuggestedBinding *s = &sb->suggestedBindings[b];
        struct action *a = action_of(s->action);
        const char *path = path_text(s->binding);
        int hand = -1;
        const char *component = path ? profile_input(pr, path, &hand) : NULL;
        if (!a)
            return XR_ERROR_HANDLE_INVALID;
        if (!component) {
            fault("%s has no input %s", profile, path ? path : "(not a path)");
            return XR_ERROR_PATH_UNSUPPORTED;
        }
        if (!type_fits(a->type, component)) {
            fault("%s: action \"%s\" cannot be bound to %s", profile, a->name, path);
            return XR_ERROR_PATH_UNSUPPORTED;
        }
        if (rt.binding_count == BINDINGS_MAX)
            return XR_ERROR_LIMIT_REACHED;
        rt.bindings[rt.binding_count++] =
            (struct binding){.profile = sb->interactionProfile, .path = s->binding, .action = a};
    }
    return XR_SUCCESS;
}

static XrResult attach_action_sets(XrSession s, const XrSessionActionSetsAttachInfo *ai)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    if (rt.attached)
        return XR_ERROR_ACTIONSETS_ALREADY_ATTACHED;
    if (ai->countActionSets != 1 || ai->actionSets[0] != ACTION_SET)
        return XR_ERROR_HANDLE_INVALID;
    rt.attached = true;
    XrPath profile = intern(rt.profile_path);
    for (int b = 0; b < rt.binding_count; b++) {
        if (rt.bindings[b].profile == profile)
            snprintf(rt.report.profile, sizeof(rt.report.profile), "%s", rt.profile_path);
    }
    rt.profile_event = true;
    return XR_SUCCESS;
}

static XrResult current_profile(XrSession s, XrPath user, XrInteractionProfileState *st)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    if (!rt.attached)
        return XR_ERROR_ACTIONSET_NOT_ATTACHED;
    const char *u = path_text(user);
    if (!u || strncmp(u, "/user/hand/", 11) != 0)
        return XR_ERROR_PATH_UNSUPPORTED;
    st->interactionProfile = rt.report.profile[0] ? intern(rt.profile_path) : XR_NULL_PATH;
    return XR_SUCCESS;
}

static XrResult sync_actions(XrSession s, const XrActionsSyncInfo *si)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    if (!rt.attached)
        return XR_ERROR_ACTIONSET_NOT_ATTACHED;
    if (rt.lost)
        return XR_ERROR_SESSION_LOST;
    rt.report.syncs++;
    if (rt.state != XR_SESSION_STATE_FOCUSED) {
        rt.synced = false;
        return XR_SESSION_NOT_FOCUSED;
    }
    rt.synced = true;
    rt.sync_frame = rt.waits > 0 ? rt.waits - 1 : 0;
    return XR_SUCCESS;
}

static bool bound(const struct action *a, int hand, const char *component_end)
{
    if (!a || !rt.report.profile[0])
        return false;
    XrPath profile = intern(rt.profile_path);
    const struct profile *pr = find_profile(rt.profile_path);
    for (int b = 0; b < rt.binding_count; b++) {
        int h = -1;
        const char *path = path_text(rt.bindings[b].path);
        if (rt.bindings[b].profile == profile && rt.bindings[b].action == a && path &&
            profile_input(pr, path, &h) && (hand < 0 || h == hand) &&
            (!component_end || ends_with(path, component_end)))
            return true;
    }
    return false;
}

/* The action's value: the largest over its bound inputs of hand H (-1: both). */
static bool action_value(XrAction h, XrPath sub, XrActionType want, float v[2])
{
    struct action *a = action_of(h);
    v[0] = v[1] = 0.0f;
    if (!a || a->type != want)
        return false;
    int hand = -1;
    if (sub != XR_NULL_PATH) {
        const char *p = path_text(sub);
        hand = p && strcmp(p, "/user/hand/left") == 0 ? 0 : 1;
    }
    if (!rt.synced)
        return false;
    XrPath profile = intern(rt.profile_path);
    const struct profile *pr = find_profile(rt.profile_path);
    bool active = false;
    for (int b = 0; b < rt.binding_count; b++) {
        const struct binding *bd = &rt.bindings[b];
        int bh = -1;
        const char *path = path_text(bd->path);
        if (bd->profile != profile || bd->action != a || !path || !profile_input(pr, path, &bh) ||
            (hand >= 0 && bh != hand))
            continue;
        active = true;
        float in[2];
        input_at(rt.sync_frame, path, in);
        if (want == XR_ACTION_TYPE_BOOLEAN_INPUT)
            in[0] = in[0] > 0.5f ? 1.0f : 0.0f;
        if (hypotf(in[0], in[1]) > hypotf(v[0], v[1])) {
            v[0] = in[0];
            v[1] = in[1];
        }
    }
    return active;
}

static XrResult get_boolean(XrSession s, const XrActionStateGetInfo *gi, XrActionStateBoolean *st)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    if (!action_of(gi->action))
        return XR_ERROR_HANDLE_INVALID;
    if (action_of(gi->action)->type != XR_ACTION_TYPE_BOOLEAN_INPUT)
        return XR_ERROR_ACTION_TYPE_MISMATCH;
    float v[2];
    st->isActive = action_value(gi->action, gi->subactionPath, XR_ACTION_TYPE_BOOLEAN_INPUT, v);
    st->currentState = v[0] > 0.5f;
    st->changedSinceLastSync = XR_FALSE;
    st->lastChangeTime = 0;
    return XR_SUCCESS;
}

static XrResult get_float(XrSession s, const XrActionStateGetInfo *gi, XrActionStateFloat *st)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    if (!action_of(gi->action))
        return XR_ERROR_HANDLE_INVALID;
    if (action_of(gi->action)->type != XR_ACTION_TYPE_FLOAT_INPUT)
        return XR_ERROR_ACTION_TYPE_MISMATCH;
    float v[2];
    st->isActive = action_value(gi->action, gi->subactionPath, XR_ACTION_TYPE_FLOAT_INPUT, v);
    st->currentState = v[0];
    st->changedSinceLastSync = XR_FALSE;
    st->lastChangeTime = 0;
    return XR_SUCCESS;
}

static XrResult get_vector2f(XrSession s, const XrActionStateGetInfo *gi, XrActionStateVector2f *st)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    if (!action_of(gi->action))
        return XR_ERROR_HANDLE_INVALID;
    if (action_of(gi->action)->type != XR_ACTION_TYPE_VECTOR2F_INPUT)
        return XR_ERROR_ACTION_TYPE_MISMATCH;
    float v[2];
    st->isActive = action_value(gi->action, gi->subactionPath, XR_ACTION_TYPE_VECTOR2F_INPUT, v);
    st->currentState = (XrVector2f){v[0], v[1]};
    st->changedSinceLastSync = XR_FALSE;
    st->lastChangeTime = 0;
    return XR_SUCCESS;
}

static XrResult get_pose(XrSession s, const XrActionStateGetInfo *gi, XrActionStatePose *st)
{
    if (!is_session(s))
        return XR_ERROR_HANDLE_INVALID;
    struct action *a = action_of(gi->action);
    if (!a)
        return XR_ERROR_HANDLE_INVALID;
    if (a->type != XR_ACTION_TYPE_POSE_INPUT)
        return XR_ERROR_ACTION_TYPE_MISMATCH;
    st->isActive = rt.synced && bound(a, -1, "/pose");
    return XR_SUCCESS;
}

static XrResult haptic(XrSession s, const XrHapticActionInfo *hi, const XrHapticBaseHeader *h)
{
    return is_session(s) ? XR_SUCCESS : XR_ERROR_HANDLE_INVALID;
}

static XrResult stop_haptic(XrSession s, const XrHapticActionInfo *hi)
{
    return is_session(s) ? XR_SUCCESS : XR_ERROR_HANDLE_INVALID;
}

/* ---- dispatch --------------------------------------------------------------------------- */

static XrResult get_proc_addr(XrInstance i, const char *name, PFN_xrVoidFunction *fn);

static const struct {
    const char *name;
    PFN_xrVoidFunction fn;
} entries[] = {
#define ENTRY(n, f)                                                                                \
    {                                                                                              \
        n, (PFN_xrVoidFunction)f                                                                   \
    }
    ENTRY("xrGetInstanceProcAddr", get_proc_addr),
    ENTRY("xrEnumerateInstanceExtensionProperties", enumerate_extensions),
    ENTRY("xrCreateInstance", create_instance),
    ENTRY("xrDestroyInstance", destroy_instance),
    ENTRY("xrGetInstanceProperties", get_instance_properties),
    ENTRY("xrPollEvent", poll_event),
    ENTRY("xrResultToString", result_to_string),
    ENTRY("xrStructureTypeToString", structure_to_string),
    ENTRY("xrStringToPath", string_to_path),
    ENTRY("xrPathToString", path_to_string),
    ENTRY("xrGetSystem", get_system),
    ENTRY("xrGetSystemProperties", get_system_properties),
    ENTRY("xrEnumerateViewConfigurations", enumerate_view_configurations),
    ENTRY("xrGetViewConfigurationProperties", get_view_configuration_properties),
    ENTRY("xrEnumerateViewConfigurationViews", enumerate_view_configuration_views),
    ENTRY("xrEnumerateEnvironmentBlendModes", enumerate_blend_modes),
    ENTRY("xrGetOpenGLGraphicsRequirementsKHR", gl_requirements),
    ENTRY("xrCreateSession", create_session),
    ENTRY("xrDestroySession", destroy_session),
    ENTRY("xrBeginSession", begin_session),
    ENTRY("xrEndSession", end_session),
    ENTRY("xrRequestExitSession", request_exit),
    ENTRY("xrEnumerateReferenceSpaces", enumerate_reference_spaces),
    ENTRY("xrCreateReferenceSpace", create_reference_space),
    ENTRY("xrGetReferenceSpaceBoundsRect", get_bounds),
    ENTRY("xrCreateActionSpace", create_action_space),
    ENTRY("xrLocateSpace", locate_space),
    ENTRY("xrDestroySpace", destroy_space),
    ENTRY("xrLocateViews", locate_views),
    ENTRY("xrEnumerateSwapchainFormats", enumerate_swapchain_formats),
    ENTRY("xrCreateSwapchain", create_swapchain),
    ENTRY("xrDestroySwapchain", destroy_swapchain),
    ENTRY("xrEnumerateSwapchainImages", enumerate_swapchain_images),
    ENTRY("xrAcquireSwapchainImage", acquire_image),
    ENTRY("xrWaitSwapchainImage", wait_image),
    ENTRY("xrReleaseSwapchainImage", release_image),
    ENTRY("xrWaitFrame", wait_frame),
    ENTRY("xrBeginFrame", begin_frame),
    ENTRY("xrEndFrame", end_frame),
    ENTRY("xrCreateActionSet", create_action_set),
    ENTRY("xrDestroyActionSet", destroy_action_set),
    ENTRY("xrCreateAction", create_action),
    ENTRY("xrDestroyAction", destroy_action),
    ENTRY("xrSuggestInteractionProfileBindings", suggest_bindings),
    ENTRY("xrAttachSessionActionSets", attach_action_sets),
    ENTRY("xrGetCurrentInteractionProfile", current_profile),
    ENTRY("xrSyncActions", sync_actions),
    ENTRY("xrGetActionStateBoolean", get_boolean),
    ENTRY("xrGetActionStateFloat", get_float),
    ENTRY("xrGetActionStateVector2f", get_vector2f),
    ENTRY("xrGetActionStatePose", get_pose),
    ENTRY("xrApplyHapticFeedback", haptic),
    ENTRY("xrStopHapticFeedback", stop_haptic),
#undef ENTRY
};

static XrResult get_proc_addr(XrInstance i, const char *name, PFN_xrVoidFunction *fn)
{
    for (size_t k = 0; k < sizeof(entries) / sizeof(entries[0]); k++) {
        if (strcmp(entries[k].name, name) == 0) {
            *fn = entries[k].fn;
            return XR_SUCCESS;
        }
    }
    *fn = NULL;
    return XR_ERROR_FUNCTION_UNSUPPORTED;
}

EXPORT XrResult xrNegotiateLoaderRuntimeInterface(const struct negotiate_loader_info *li,
                                                  struct negotiate_runtime_request *rr)
{
    if (!li || li->structType != LOADER_INFO || li->structVersion != 1 ||
        li->structSize != sizeof(*li) || !rr || rr->structType != RUNTIME_REQUEST ||
        rr->structVersion != 1 || rr->structSize != sizeof(*rr))
        return XR_ERROR_INITIALIZATION_FAILED;
    if (li->minInterfaceVersion > 1 || li->maxInterfaceVersion < 1 ||
        XR_VERSION_MAJOR(li->maxApiVersion) < 1 || XR_VERSION_MAJOR(li->minApiVersion) > 1)
        return XR_ERROR_INITIALIZATION_FAILED;
    rr->runtimeInterfaceVersion = 1;
    rr->runtimeApiVersion = XR_CURRENT_API_VERSION;
    rr->getInstanceProcAddr = get_proc_addr;
    return XR_SUCCESS;
}

/* ---- the side door (runtime.h) ----------------------------------------------------------- */

EXPORT bool anvil_xr_test_script(const char *text)
{
    load_script();
    return script_text(text);
}

EXPORT bool anvil_xr_test_reset(const char *text)
{
    if (rt.instance_live)
        return false;
    for (int e = 0; e < 2; e++) {
        free(rt.image[e]);
        rt.image[e] = NULL;
    }
    memset(&rt.report, 0, sizeof(rt.report));
    rt.event_count = 0;
    rt.waits = 0;
    rt.frame_time = 0;
    rt.loaded = true;
    defaults();
    return !text || script_text(text);
}

EXPORT void anvil_xr_test_get_report(struct anvil_xr_test_report *out)
{
    *out = rt.report;
}

EXPORT const uint8_t *anvil_xr_test_image(int eye, int *w, int *h)
{
    if (eye < 0 || eye > 1 || !rt.image[eye])
        return NULL;
    *w = rt.image_size[eye][0];
    *h = rt.image_size[eye][1];
    return rt.image[eye];
}
