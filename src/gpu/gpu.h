/*
 * gpu: the only part that calls OpenGL, EGL or GLFW's context functions.  It gives the rest
 * of the program contexts (headless EGL or a GLFW window, behind one table), compute
 * programs loaded from shaders/ with #include and #define variants, textures, storage
 * buffers and timer queries, so that no other part includes a GL header.
 *
 * Every function except gpu_context_* needs a context current on the calling thread.
 *
 * Must not know: scenes, volumes, physics, configs; it is the only part that calls OpenGL, EGL
 * or GLFW's context functions.
 */
#ifndef ANVIL_GPU_H
#define ANVIL_GPU_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* ---- contexts ---------------------------------------------------------------------- */

struct gpu_context;

struct gpu_context_desc {
    const char *backend; /* "egl" (headless) or "glfw" (window); NULL = "egl" */
    int width, height;   /* window size (glfw); ignored headless */
    const char *title;   /* window title */
    bool debug;          /* GL debug output to the log (default on: zero means on) */
    bool no_debug;       /* set to turn the debug output off */
    void *share_window;  /* glfw: a GLFWwindow to share objects with, or NULL */
    int monitor;         /* glfw: monitor index for fullscreen, -1 = windowed */
    bool stereo;         /* glfw: ask for a quad-buffer stereo framebuffer */
    int device;          /* egl: the GPU by index among the EGL devices (modulo how many there
                            are): one per rank of a node; 0 = the first platform that works */
    bool egl_config;     /* egl: make the context from an EGLConfig even where
                            EGL_KHR_no_config_context allows none (a runtime that shares the
                            context makes its own from the same config: OpenXR) */
    const char *output;  /* glfw: fullscreen on the output of this name (before MONITOR);
                            NULL or "": none */
    bool rect_set;       /* glfw: RECT places the window (before MONITOR, after OUTPUT) */
    int rect[4];         /* [x, y, w, h] on the desktop: fullscreen on the output exactly
                            there, else a borderless window of that place and size */
};

/* An output (GLFW's monitor): its name and its rectangle on the desktop, in screen
 * coordinates. */
struct gpu_output {
    char name[64];
    int rect[4]; /* x, y, w, h */
};

/* The output among N called NAME: the same name, else the same ignoring case; -1 if none. */
int gpu_output_by_name(const struct gpu_output *outputs, int n, const char *name);
/* The output among N whose rectangle is RECT exactly; -1 if none. */
int gpu_output_by_rect(const struct gpu_output *outputs, int n, const int rect[4]);
/* "DP-1 at 0,0 1920x1080; HDMI-0 at 1920,0 1920x1080" (or "none") into OUT. */
void gpu_output_list(const struct gpu_output *outputs, int n, char *out, size_t size);
/* Where DESC puts a window among the N OUTPUTS: the output index to be fullscreen on, or -1
 * for a window (then *BORDERLESS says whether at DESC->rect).  A name or place that matches no
 * output is warned about, with the outputs there are, and gives a window. */
int gpu_output_choose(const struct gpu_context_desc *desc, const struct gpu_output *outputs,
                      int n, bool *borderless);

/* Creates an OpenGL 4.5 core context and makes it current.  Returns NULL (reason logged) when
 * no such context can be made: tests then exit 77.  Destroy with gpu_context_destroy. */
struct gpu_context *gpu_context_create(const struct gpu_context_desc *desc);
void gpu_context_destroy(struct gpu_context *ctx);
void gpu_context_make_current(struct gpu_context *ctx);
const char *gpu_context_backend(const struct gpu_context *ctx);
/* Prints the backends one per line with a description (for --display help and docs). */
void gpu_context_list(void (*print)(const char *name, const char *what, void *user), void *user);

/* Window contexts: the GLFWwindow (as void *), NULL for headless.  Valid until destroy. */
void *gpu_context_window(struct gpu_context *ctx);
bool gpu_context_has_stereo(const struct gpu_context *ctx);
void gpu_context_swap(struct gpu_context *ctx);
/* Makes CTX current and sets how many vertical blanks its swaps wait for (0: none).  Windows
 * that swap together wait in the last one only.  No effect on headless contexts (nor on
 * NULL). */
void gpu_context_swap_interval(struct gpu_context *ctx, int interval);
/* Makes CTX current and joins its window to swap group GROUP bound to barrier BARRIER (0:
 * none), so that windows of several processes and machines swap together (GLX_NV_swap_group
 * with a framelock board).  False where the window system has no swap groups (headless, Mesa,
 * Wayland): the caller keeps its own barrier. */
bool gpu_context_join_swap_group(struct gpu_context *ctx, unsigned group, unsigned barrier);
/* Framebuffer size of a window context; the desc size for headless. */
void gpu_context_size(struct gpu_context *ctx, int *width, int *height);

/* Renderer and version strings of the current context (static storage). */
const char *gpu_renderer_name(void);

/* ---- textures ------------------------------------------------------------------------ */

enum gpu_format { GPU_R32F, GPU_RG32F, GPU_RGBA32F, GPU_RGBA8, GPU_R16F, GPU_RG16F, GPU_R32UI };

struct gpu_texture {
    unsigned id;
    int dims;          /* 1, 2 or 3 */
    int size[3];
    enum gpu_format format;
    size_t bytes;
};

/* Creates a texture with linear filtering and clamp-to-edge; DATA (may be NULL) is tightly
 * packed float (uint8 for GPU_RGBA8, uint32 for GPU_R32UI), x fastest.  Returns false (logged) on failure. */
bool gpu_texture_init(struct gpu_texture *tex, int dims, const int size[3],
                      enum gpu_format format, const void *data);
/* Sets every texel of level 0 to zero. */
void gpu_texture_clear(struct gpu_texture *tex);
/* Replaces the whole content; same layout as init. */
void gpu_texture_upload(struct gpu_texture *tex, const void *data);
/* Replaces the layers Z0 .. Z0 + COUNT - 1 of a 3D texture; DATA as for init, those layers
 * only. */
void gpu_texture_upload_layers(struct gpu_texture *tex, int z0, int count, const void *data);
/* Reads the whole level 0 back into OUT (bytes as for init, float or uint8). */
void gpu_texture_read(const struct gpu_texture *tex, void *out, size_t out_bytes);
/* Reads the box of SIZE texels from OFFSET of level 0 (3D: x, y, z; 2D: z = 0, size[2] = 1)
 * into OUT, tightly packed as for init.  Waits for the GPU work that writes the texture. */
void gpu_texture_read_region(const struct gpu_texture *tex, const int offset[3],
                             const int size[3], void *out, size_t out_bytes);
void gpu_texture_finish(struct gpu_texture *tex);
/* Copies TEX's level 0 into the 2D texture named DST (a texture this part did not make, such
 * as an OpenXR swapchain image), which must be as large and of a format of the same size
 * class (RGBA8 into an sRGB8 alpha8 image: the bytes are copied as they are). */
void gpu_texture_copy_into(const struct gpu_texture *tex, unsigned dst);
/* Binds for sampling at texture unit UNIT. */
void gpu_texture_bind(const struct gpu_texture *tex, unsigned unit);
/* Binds level 0 as an image at image unit UNIT (write-only when WRITE, else read-only). */
void gpu_image_bind(const struct gpu_texture *tex, unsigned unit, bool write);
void gpu_image_bind_rw(const struct gpu_texture *tex, unsigned unit);

/* ---- storage buffers ----------------------------------------------------------------- */

struct gpu_buffer {
    unsigned id;
    size_t bytes;
};

bool gpu_buffer_init(struct gpu_buffer *buf, size_t bytes, const void *data);
void gpu_buffer_upload(struct gpu_buffer *buf, size_t offset, size_t bytes, const void *data);
void gpu_buffer_read(const struct gpu_buffer *buf, size_t offset, size_t bytes, void *out);
void gpu_buffer_bind(const struct gpu_buffer *buf, unsigned binding);
void gpu_buffer_finish(struct gpu_buffer *buf);

/* ---- pixel-buffer uploads ------------------------------------------------------------- */

/* A buffer mapped persistently into this process's memory: any thread may write MAP (no GL
 * call needed for that), then the context's thread uploads from it into textures
 * (gpu_texture_upload_from) without the driver copying client memory while a frame waits.
 * MAP is valid until gpu_upload_buffer_finish; writes are seen by the GPU without a flush
 * (coherent), but the caller must not rewrite a region before the fence of the uploads that
 * read it has passed (gpu_fence_insert). */
struct gpu_upload_buffer {
    unsigned id;
    size_t bytes;
    void *map;
};

bool gpu_upload_buffer_init(struct gpu_upload_buffer *buf, size_t bytes);
void gpu_upload_buffer_finish(struct gpu_upload_buffer *buf);
/* Replaces the layers Z0 .. Z0 + COUNT - 1 of TEX (a 3D texture; for 2D, Z0 0 and COUNT 1)
 * with the data at byte OFFSET of BUF, laid out as for gpu_texture_init.  Queued: returns
 * without waiting for the copy. */
void gpu_texture_upload_from(struct gpu_texture *tex, const struct gpu_upload_buffer *buf,
                             size_t offset, int z0, int count);

/* A fence after the GL work issued so far (0 when none could be made: then treat it as
 * passed).  gpu_fence_passed never waits; every fence made is deleted with gpu_fence_delete. */
uint64_t gpu_fence_insert(void);
bool gpu_fence_passed(uint64_t fence);
void gpu_fence_delete(uint64_t fence);

/* Bytes currently held by textures and buffers made through this part. */
size_t gpu_bytes_allocated(void);

/* ---- compute programs ---------------------------------------------------------------- */

struct gpu_program {
    unsigned id;
    int local_size[3];
};

/* Compiles shaders/NAME as a compute shader.  "#version 450 core" comes first, then DEFINES
 * (lines like "#define SHADOWS 1\n", may be NULL), then the file, where a line
 * `#include "FILE"` is replaced by shaders/FILE (nested, each file once): a GLSL include
 * (*.glsl) or shaders/bindings.h, the binding numbers C includes too.  #line directives keep
 * every file's own line numbers, so compile and link errors are logged with the file name and
 * line.  The shader directory is $ANVIL_SHADER_DIR if set, else the source tree's shaders/. */
bool gpu_program_init(struct gpu_program *prog, const char *name, const char *defines);
/* A vertex + fragment program from shaders/VERTEX and shaders/FRAGMENT, loaded like compute
 * programs (same #include and DEFINES handling). */
bool gpu_program_init_graphics(struct gpu_program *prog, const char *vertex,
                               const char *fragment, const char *defines);
void gpu_program_finish(struct gpu_program *prog);
void gpu_program_use(const struct gpu_program *prog);

/* Uniform setters on the program (no need to use it first); a name the compiler removed is
 * ignored. */
void gpu_uniform_int(const struct gpu_program *p, const char *name, int v);
void gpu_uniform_float(const struct gpu_program *p, const char *name, float v);
void gpu_uniform_uint(const struct gpu_program *p, const char *name, unsigned v);
void gpu_uniform_double(const struct gpu_program *p, const char *name, double v);
void gpu_uniform_vec2(const struct gpu_program *p, const char *name, const float v[2]);
void gpu_uniform_vec3(const struct gpu_program *p, const char *name, const float v[3]);
void gpu_uniform_ivec2(const struct gpu_program *p, const char *name, const int v[2]);
void gpu_uniform_ivec3(const struct gpu_program *p, const char *name, const int v[3]);
/* COUNT ivec4 of V (4 * COUNT ints) into the uniform array NAME from its element 0. */
void gpu_uniform_ivec4_array(const struct gpu_program *p, const char *name, int count,
                             const int *v);
void gpu_uniform_vec4(const struct gpu_program *p, const char *name, const float v[4]);
/* COUNT floats of V into the uniform array NAME from its element 0. */
void gpu_uniform_float_array(const struct gpu_program *p, const char *name, int count,
                             const float *v);
void gpu_uniform_mat4(const struct gpu_program *p, const char *name, const float m[16]);

/* Runs PROG over enough groups to cover W x H x D invocations, then a memory barrier so the
 * next dispatch, texture fetch or read-back sees the writes. */
void gpu_dispatch(const struct gpu_program *prog, int w, int h, int d);

/* Runs PROG over the work groups that ARGS holds at byte OFFSET (three uint32: groups along
 * x, y, z, as an earlier dispatch wrote them), then the same barrier as gpu_dispatch. */
void gpu_dispatch_indirect(const struct gpu_program *prog, const struct gpu_buffer *args,
                           size_t offset);

/* Waits for all GL work. */
void gpu_finish(void);

/* ---- meshes and render targets (graphics.c) ------------------------------------------ */

/* Interleaved float vertices: ATTRIB_SIZES[i] floats for attribute location i. */
struct gpu_mesh {
    unsigned vao, vbo, ibo;
    int index_count;
    bool lines; /* GL_LINES instead of GL_TRIANGLES */
    size_t bytes;
};

bool gpu_mesh_init(struct gpu_mesh *mesh, const float *vertices, int vertex_count,
                   const int *attrib_sizes, int attrib_count, const uint32_t *indices,
                   int index_count, bool lines);
void gpu_mesh_finish(struct gpu_mesh *mesh);
/* Draws MESH with PROG into the bound target (depth-tested, no blending). */
void gpu_mesh_draw(const struct gpu_mesh *mesh, const struct gpu_program *prog);

/* An offscreen target: two float colour attachments (location 0: RGBA32F, location 1: R32F)
 * and a depth buffer. */
struct gpu_target {
    unsigned fbo, depth;
    struct gpu_texture color, value;
    int width, height;
};

/* Creates or resizes T.  Returns false (logged) on failure. */
bool gpu_target_ensure(struct gpu_target *t, int width, int height);
void gpu_target_finish(struct gpu_target *t);
/* Binds T for drawing, clears colour to CLEAR_COLOR, the R32F value to CLEAR_VALUE, depth to 1.
 * gpu_target_end binds the default framebuffer again and makes the writes visible to compute
 * shaders and texture fetches. */
void gpu_target_begin(struct gpu_target *t, const float clear_color[4], float clear_value);
void gpu_target_end(struct gpu_target *t);

/* ---- presenting to a window ---------------------------------------------------------- */

/* Copies an RGBA8 texture into the current default framebuffer's region (x, y, w, h), into
 * the back-left, back-right or back buffer as BUFFER says (0 back, 1 back-left, 2 back-right). */
void gpu_present(const struct gpu_texture *tex, int x, int y, int w, int h, int buffer);
void gpu_clear_default(float r, float g, float b);

/* ---- sharing a context with an OpenXR runtime (context_xr.c; built with the OpenXR
 * loader only, HAVE_OPENXR) ------------------------------------------------------------- */

#define GPU_XR_BINDING_BYTES 128

/* Fills BINDING (GPU_XR_BINDING_BYTES of caller storage aligned for pointers) with the OpenXR
 * graphics binding of CTX, the structure XrSessionCreateInfo.next points to:
 * XrGraphicsBindingEGLMNDX for an "egl" context, XrGraphicsBindingOpenGLXlibKHR for a "glfw"
 * window on X11.  Returns the instance extension the binding needs besides
 * XR_KHR_opengl_enable ("XR_MNDX_egl_enable"; "" for Xlib), or NULL (logged) when CTX has no
 * such binding.  The handles in it stay valid while CTX does. */
const char *gpu_context_xr_binding(struct gpu_context *ctx, void *binding);

/* The swapchain format anvil writes, GL_SRGB8_ALPHA8 (the tone-mapped RGBA8 image copied as it
 * is), if it is among the COUNT FORMATS a runtime offers (xrEnumerateSwapchainFormats);
 * else 0. */
int64_t gpu_xr_swapchain_format(const int64_t *formats, int count);

/* ---- timers --------------------------------------------------------------------------
 * Timing never makes the CPU wait for the GPU: a measurement brackets GPU work with two
 * GL_TIMESTAMP queries, and its time is read later, once the GPU has passed the second one
 * (GL_QUERY_RESULT_AVAILABLE), into a log the caller owns.  Only a collect that is asked to
 * wait (at the end of a run, for a report) or a full queue waits.
 *
 * Software drivers (Mesa's llvmpipe and softpipe) are the exception: they run compute work
 * on the calling thread and their timestamps do not advance across it, so there the end of a
 * measurement waits for the work (glFinish) and the wall time since its beginning is the
 * result, known at once.  Timing blocks there by nature. */

/* Measured times, numbered from 1 in the order the measurements ended.  Plain data, zero =
 * empty: whoever reads it owns it, and lends it to the code that measures. */
#define GPU_TIMINGS_KEPT 64
struct gpu_timings {
    unsigned count;                /* measurements ended */
    unsigned arrived;              /* of them, those whose GPU time was read */
    double total_ms;               /* the sum of every time that arrived or was added */
    double ms[GPU_TIMINGS_KEPT];   /* measurement i at ms[i - 1], the first GPU_TIMINGS_KEPT */
    bool known[GPU_TIMINGS_KEPT];  /* whether ms[i - 1] arrived */
};

/* Adds MS to measurement NUMBER of LOG (CPU work a measurement includes, such as compressing
 * a light map on the CPU), whether or not its GPU time arrived yet. */
void gpu_timings_add(struct gpu_timings *log, unsigned number, double ms);

/* Whether the current context's driver is one of those (it then shares the CPU's cores with
 * the caller: work off the render thread competes with the frame's). */
bool gpu_software_driver(void);

/* Whether the current context offers the OpenGL extension NAME ("GL_ARB_shader_ballot"). */
bool gpu_has_extension(const char *name);

/* How a queue measures.  AUTO (zero) takes WALL on software drivers and QUERIES elsewhere;
 * QUERIES there would measure next to nothing, but follows the same bookkeeping (tests). */
enum gpu_timer_clock { GPU_TIMER_AUTO, GPU_TIMER_QUERIES, GPU_TIMER_WALL };

/* Measurements in flight, oldest first.  Caller-owned memory; init, begin, end, collect and
 * finish need the GL context current. */
#define GPU_TIMER_QUEUE_SIZE 64
struct gpu_timer_queue {
    struct gpu_timer_slot {
        unsigned query[2];        /* GL_TIMESTAMP before and after */
        struct gpu_timings *log;  /* where its time goes */
        unsigned number;          /* its number in LOG */
    } slot[GPU_TIMER_QUEUE_SIZE];
    int head, pending;            /* the oldest measurement in flight, how many are */
    bool running;                 /* begun and not ended */
    double cpu_start;             /* wall clock at begin (software drivers) */
    bool wall_clock;              /* software driver: wall time around a glFinish */
    double last_ms;               /* the time of the latest measurement that arrived */
};

void gpu_timer_queue_init(struct gpu_timer_queue *q, enum gpu_timer_clock clock);
/* Deletes the queries; times still in flight are dropped (their logs are not written). */
void gpu_timer_queue_finish(struct gpu_timer_queue *q);
/* Begins a measurement.  With GPU_TIMER_QUEUE_SIZE in flight, the oldest is waited for
 * first: a bound on the queries a caller that never collects holds. */
void gpu_timer_queue_begin(struct gpu_timer_queue *q);
/* Ends the measurement begun last as measurement number ++LOG->count of LOG, and returns that
 * number; 0 (LOG untouched) when none was begun.  LOG must stay valid until its time arrived
 * (gpu_timer_queue_collect) or the queue is finished.  Does not wait, but on software
 * drivers. */
unsigned gpu_timer_queue_end(struct gpu_timer_queue *q, struct gpu_timings *log);
/* Moves the times the GPU has ready into their logs, oldest first, without waiting; with
 * WAIT, waits for all of them.  Returns how many are still in flight (0 after a WAIT). */
int gpu_timer_queue_collect(struct gpu_timer_queue *q, bool wait);

#endif
