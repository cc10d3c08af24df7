#include "gpu/gpu.h"

#include <assert.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <epoxy/gl.h>

#include "common/log.h"

static atomic_size_t bytes_allocated;

size_t gpu_bytes_allocated(void)
{
    return atomic_load(&bytes_allocated);
}

/* ---- textures ------------------------------------------------------------------------ */

struct format_info {
    GLenum internal, format, type;
    size_t texel_bytes; /* of the client-side data */
};

static struct format_info format_info(enum gpu_format f)
{
    switch (f) {
    case GPU_R32F:
        return (struct format_info){GL_R32F, GL_RED, GL_FLOAT, 4};
    case GPU_RG32F:
        return (struct format_info){GL_RG32F, GL_RG, GL_FLOAT, 8};
    case GPU_RGBA32F:
        return (struct format_info){GL_RGBA32F, GL_RGBA, GL_FLOAT, 16};
    case GPU_RGBA8:
        return (struct format_info){GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, 4};
    case GPU_R16F:
        return (struct format_info){GL_R16F, GL_RED, GL_FLOAT, 4};
    case GPU_RG16F:
        return (struct format_info){GL_RG16F, GL_RG, GL_FLOAT, 8};
    case GPU_R32UI:
        return (struct format_info){GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, 4};
    }
    return (struct format_info){GL_RGBA32F, GL_RGBA, GL_FLOAT, 16};
}

static size_t device_texel_bytes(enum gpu_format f)
{
    switch (f) {
    case GPU_R16F:
        return 2;
    case GPU_RG16F:
        return 4;
    default:
        return format_info(f).texel_bytes;
    }
}

static size_t texel_count(const struct gpu_texture *t)
{
    size_t n = (size_t)t->size[0];
    if (t->dims > 1)
        n *= (size_t)t->size[1];
    if (t->dims > 2)
        n *= (size_t)t->size[2];
    return n;
}

bool gpu_texture_init(struct gpu_texture *tex, int dims, const int size[3],
                      enum gpu_format format, const void *data)
{
    memset(tex, 0, sizeof(*tex));
    tex->dims = dims;
    tex->format = format;
    for (int i = 0; i < 3; i++)
        tex->size[i] = i < dims ? size[i] : 1;
    GLint max3d = 0, max2d = 0;
    glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max3d);
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max2d);
    int limit = dims == 3 ? max3d : max2d;
    for (int i = 0; i < dims; i++) {
        if (tex->size[i] < 1 || tex->size[i] > limit) {
            log_error("texture size %d is outside this GPU's range [1, %d]", tex->size[i],
                      limit);
            return false;
        }
    }
    GLenum target = dims == 1 ? GL_TEXTURE_1D : dims == 2 ? GL_TEXTURE_2D : GL_TEXTURE_3D;
    struct format_info fi = format_info(format);
    glCreateTextures(target, 1, &tex->id);
    while (glGetError() != GL_NO_ERROR) {
    }
    if (dims == 1)
        glTextureStorage1D(tex->id, 1, fi.internal, tex->size[0]);
    else if (dims == 2)
        glTextureStorage2D(tex->id, 1, fi.internal, tex->size[0], tex->size[1]);
    else
        glTextureStorage3D(tex->id, 1, fi.internal, tex->size[0], tex->size[1], tex->size[2]);
    if (glGetError() != GL_NO_ERROR) {
        log_error("the GPU could not allocate a %dx%dx%d texture", tex->size[0], tex->size[1],
                  tex->size[2]);
        glDeleteTextures(1, &tex->id);
        tex->id = 0;
        return false;
    }
    GLint filter = format == GPU_R32UI ? GL_NEAREST : GL_LINEAR; /* integers: no filtering */
    glTextureParameteri(tex->id, GL_TEXTURE_MIN_FILTER, filter);
    glTextureParameteri(tex->id, GL_TEXTURE_MAG_FILTER, filter);
    glTextureParameteri(tex->id, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(tex->id, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTextureParameteri(tex->id, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
    tex->bytes = texel_count(tex) * device_texel_bytes(format);
    atomic_fetch_add(&bytes_allocated, tex->bytes);
    if (data)
        gpu_texture_upload(tex, data);
    return true;
}

void gpu_texture_upload(struct gpu_texture *tex, const void *data)
{
    struct format_info fi = format_info(tex->format);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    if (tex->dims == 1)
        glTextureSubImage1D(tex->id, 0, 0, tex->size[0], fi.format, fi.type, data);
    else if (tex->dims == 2)
        glTextureSubImage2D(tex->id, 0, 0, 0, tex->size[0], tex->size[1], fi.format, fi.type,
                            data);
    else
        glTextureSubImage3D(tex->id, 0, 0, 0, 0, tex->size[0], tex->size[1], tex->size[2],
                            fi.format, fi.type, data);
}

void gpu_texture_upload_layers(struct gpu_texture *tex, int z0, int count, const void *data)
{
    struct format_info fi = format_info(tex->format);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTextureSubImage3D(tex->id, 0, 0, 0, z0, tex->size[0], tex->size[1], count, fi.format,
                        fi.type, data);
}

void gpu_texture_clear(struct gpu_texture *tex)
{
    struct format_info fi = format_info(tex->format);
    glClearTexImage(tex->id, 0, fi.format, fi.type, NULL);
}

void gpu_texture_read(const struct gpu_texture *tex, void *out, size_t out_bytes)
{
    struct format_info fi = format_info(tex->format);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glGetTextureImage(tex->id, 0, fi.format, fi.type, (GLsizei)out_bytes, out);
}

void gpu_texture_read_region(const struct gpu_texture *tex, const int offset[3],
                             const int size[3], void *out, size_t out_bytes)
{
    struct format_info fi = format_info(tex->format);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glGetTextureSubImage(tex->id, 0, offset[0], offset[1], offset[2], size[0], size[1], size[2],
                         fi.format, fi.type, (GLsizei)out_bytes, out);
}

void gpu_texture_finish(struct gpu_texture *tex)
{
    if (!tex || !tex->id)
        return;
    glDeleteTextures(1, &tex->id);
    atomic_fetch_sub(&bytes_allocated, tex->bytes);
    memset(tex, 0, sizeof(*tex));
}

void gpu_texture_copy_into(const struct gpu_texture *tex, unsigned dst)
{
    glCopyImageSubData(tex->id, GL_TEXTURE_2D, 0, 0, 0, 0, dst, GL_TEXTURE_2D, 0, 0, 0, 0,
                       tex->size[0], tex->size[1], 1);
}

void gpu_texture_bind(const struct gpu_texture *tex, unsigned unit)
{
    glBindTextureUnit(unit, tex->id);
}

void gpu_image_bind(const struct gpu_texture *tex, unsigned unit, bool write)
{
    glBindImageTexture(unit, tex->id, 0, tex->dims == 3 ? GL_TRUE : GL_FALSE, 0,
                       write ? GL_WRITE_ONLY : GL_READ_ONLY, format_info(tex->format).internal);
}

void gpu_image_bind_rw(const struct gpu_texture *tex, unsigned unit)
{
    glBindImageTexture(unit, tex->id, 0, tex->dims == 3 ? GL_TRUE : GL_FALSE, 0, GL_READ_WRITE,
                       format_info(tex->format).internal);
}

/* ---- buffers ------------------------------------------------------------------------- */

/* ---- pixel-buffer uploads ------------------------------------------------------------- */

bool gpu_upload_buffer_init(struct gpu_upload_buffer *buf, size_t bytes)
{
    memset(buf, 0, sizeof(*buf));
    const GLbitfield flags = GL_MAP_WRITE_BIT | GL_MAP_PERSISTENT_BIT | GL_MAP_COHERENT_BIT;
    glCreateBuffers(1, &buf->id);
    while (glGetError() != GL_NO_ERROR) {
    }
    glNamedBufferStorage(buf->id, (GLsizeiptr)(bytes ? bytes : 4), NULL, flags);
    if (glGetError() == GL_NO_ERROR)
        buf->map = glMapNamedBufferRange(buf->id, 0, (GLsizeiptr)(bytes ? bytes : 4), flags);
    if (!buf->map) {
        log_error("the GPU could not map a pixel buffer of %zu bytes", bytes);
        glDeleteBuffers(1, &buf->id);
        buf->id = 0;
        return false;
    }
    buf->bytes = bytes;
    atomic_fetch_add(&bytes_allocated, bytes);
    return true;
}

void gpu_upload_buffer_finish(struct gpu_upload_buffer *buf)
{
    if (buf->id) {
        glUnmapNamedBuffer(buf->id);
        glDeleteBuffers(1, &buf->id);
        atomic_fetch_sub(&bytes_allocated, buf->bytes);
    }
    memset(buf, 0, sizeof(*buf));
}

void gpu_texture_upload_from(struct gpu_texture *tex, const struct gpu_upload_buffer *buf,
                             size_t offset, int z0, int count)
{
    struct format_info fi = format_info(tex->format);
    assert(offset + texel_count(tex) / (size_t)tex->size[2] * (size_t)count * fi.texel_bytes <=
           buf->bytes);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, buf->id);
    const void *at = (const void *)(uintptr_t)offset; /* an offset into the bound buffer */
    if (tex->dims == 2)
        glTextureSubImage2D(tex->id, 0, 0, 0, tex->size[0], tex->size[1], fi.format, fi.type,
                            at);
    else
        glTextureSubImage3D(tex->id, 0, 0, 0, z0, tex->size[0], tex->size[1], count, fi.format,
                            fi.type, at);
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
}

uint64_t gpu_fence_insert(void)
{
    GLsync sync = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
    glFlush(); /* so that the fence is reached without anyone waiting on it */
    return (uint64_t)(uintptr_t)sync;
}

bool gpu_fence_passed(uint64_t fence)
{
    if (!fence)
        return true;
    GLenum r = glClientWaitSync((GLsync)(uintptr_t)fence, 0, 0);
    return r == GL_ALREADY_SIGNALED || r == GL_CONDITION_SATISFIED || r == GL_WAIT_FAILED;
}

void gpu_fence_delete(uint64_t fence)
{
    if (fence)
        glDeleteSync((GLsync)(uintptr_t)fence);
}

bool gpu_buffer_init(struct gpu_buffer *buf, size_t bytes, const void *data)
{
    memset(buf, 0, sizeof(*buf));
    glCreateBuffers(1, &buf->id);
    while (glGetError() != GL_NO_ERROR) {
    }
    glNamedBufferStorage(buf->id, (GLsizeiptr)(bytes ? bytes : 4), data,
                         GL_DYNAMIC_STORAGE_BIT | GL_MAP_READ_BIT);
    if (glGetError() != GL_NO_ERROR) {
        log_error("the GPU could not allocate a buffer of %zu bytes", bytes);
        glDeleteBuffers(1, &buf->id);
        buf->id = 0;
        return false;
    }
    buf->bytes = bytes;
    atomic_fetch_add(&bytes_allocated, bytes);
    return true;
}

void gpu_buffer_upload(struct gpu_buffer *buf, size_t offset, size_t bytes, const void *data)
{
    glNamedBufferSubData(buf->id, (GLintptr)offset, (GLsizeiptr)bytes, data);
}

void gpu_buffer_read(const struct gpu_buffer *buf, size_t offset, size_t bytes, void *out)
{
    glGetNamedBufferSubData(buf->id, (GLintptr)offset, (GLsizeiptr)bytes, out);
}

void gpu_buffer_bind(const struct gpu_buffer *buf, unsigned binding)
{
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, binding, buf->id);
}

void gpu_buffer_finish(struct gpu_buffer *buf)
{
    if (!buf || !buf->id)
        return;
    glDeleteBuffers(1, &buf->id);
    atomic_fetch_sub(&bytes_allocated, buf->bytes);
    memset(buf, 0, sizeof(*buf));
}

/* ---- programs ------------------------------------------------------------------------ */

static const char *shader_dir(void)
{
    const char *env = getenv("ANVIL_SHADER_DIR");
    return env && *env ? env : ANVIL_SHADER_DIR;
}

struct source {
    char *text;
    size_t len, cap;
    char included[32][128]; /* files already pasted in (each once) */
    int n_included;
    /* Maps GLSL's #line file numbers to names for error messages. */
    char names[32][128];
    int n_names;
};

static bool append(struct source *s, const char *text, size_t len)
{
    if (s->len + len + 1 > s->cap) {
        size_t cap = (s->cap ? s->cap : 4096);
        while (cap < s->len + len + 1)
            cap *= 2;
        char *grown = realloc(s->text, cap);
        if (!grown) {
            log_error("out of memory reading shaders");
            return false;
        }
        s->text = grown;
        s->cap = cap;
    }
    memcpy(s->text + s->len, text, len);
    s->len += len;
    s->text[s->len] = '\0';
    return true;
}

static bool appendf(struct source *s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static bool appendf(struct source *s, const char *fmt, ...)
{
    char buf[512];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(buf, sizeof(buf), fmt, ap);
    va_end(ap);
    return append(s, buf, (size_t)n);
}

static bool load_file(struct source *s, const char *name, int depth)
{
    if (depth > 16) {
        log_error("shaders/%s: #include nested too deeply", name);
        return false;
    }
    for (int i = 0; i < s->n_included; i++) {
        if (strcmp(s->included[i], name) == 0)
            return true;
    }
    if (s->n_included >= 32 || s->n_names >= 32) {
        log_error("shaders/%s: too many included files", name);
        return false;
    }
    snprintf(s->included[s->n_included++], 128, "%s", name);
    int file_no = s->n_names;
    snprintf(s->names[s->n_names++], 128, "%s", name);

    char path[1024];
    snprintf(path, sizeof(path), "%s/%s", shader_dir(), name);
    char *text = file_read_all(path, NULL);
    if (!text)
        return false;
    bool ok = appendf(s, "#line 1 %d\n", file_no);
    int line = 1;
    for (char *p = text; ok && *p;) {
        char *end = strchr(p, '\n');
        size_t len = end ? (size_t)(end - p) : strlen(p);
        const char *q = p;
        while (*q == ' ' || *q == '\t')
            q++;
        if (strncmp(q, "#include", 8) == 0) {
            const char *open = strchr(q, '"');
            const char *close = open ? strchr(open + 1, '"') : NULL;
            if (!open || !close || close > p + len) {
                log_error("shaders/%s:%d: expected #include \"FILE\" (a file in shaders/)", name,
                          line);
                ok = false;
                break;
            }
            char inc[128];
            snprintf(inc, sizeof(inc), "%.*s", (int)(close - open - 1), open + 1);
            ok = load_file(s, inc, depth + 1) && appendf(s, "#line %d %d\n", line + 1, file_no);
        } else {
            ok = append(s, p, len) && append(s, "\n", 1);
        }
        line++;
        p = end ? end + 1 : p + len;
    }
    free(text);
    return ok;
}

/* Rewrites "0(12)" / "0:12" style file numbers in the compiler log to file names. */
static void log_compile_errors(const struct source *s, const char *name, const char *log)
{
    log_error("shaders/%s: compile failed:", name);
    for (const char *p = log; *p;) {
        const char *end = strchr(p, '\n');
        size_t len = end ? (size_t)(end - p) : strlen(p);
        int file_no = -1, line = 0;
        if (sscanf(p, "%d:%d", &file_no, &line) == 2 ||
            sscanf(p, "%d(%d)", &file_no, &line) == 2) {
            const char *fname = file_no >= 0 && file_no < s->n_names ? s->names[file_no] : "?";
            log_error("  shaders/%s:%d: %.*s", fname, line, (int)len, p);
        } else if (len > 0) {
            log_error("  %.*s", (int)len, p);
        }
        p = end ? end + 1 : p + len;
    }
}

/* Compiles one stage of shaders/NAME with DEFINES; 0 (logged) on failure. */
static GLuint compile_stage(const char *name, const char *defines, GLenum type)
{
    struct source s = {0};
    bool ok = appendf(&s, "#version 450 core\n") &&
              (!defines || append(&s, defines, strlen(defines))) && append(&s, "\n", 1) &&
              load_file(&s, name, 0);
    if (!ok) {
        free(s.text);
        return 0;
    }
    GLuint sh = glCreateShader(type);
    const GLchar *src = s.text;
    glShaderSource(sh, 1, &src, NULL);
    glCompileShader(sh);
    GLint status = 0;
    glGetShaderiv(sh, GL_COMPILE_STATUS, &status);
    if (!status) {
        char log[8192];
        glGetShaderInfoLog(sh, sizeof(log), NULL, log);
        log_compile_errors(&s, name, log);
        glDeleteShader(sh);
        sh = 0;
    }
    free(s.text);
    return sh;
}

static bool link_program(struct gpu_program *prog, const char *name, const GLuint *stages,
                         int n)
{
    prog->id = glCreateProgram();
    for (int i = 0; i < n; i++)
        glAttachShader(prog->id, stages[i]);
    glLinkProgram(prog->id);
    for (int i = 0; i < n; i++)
        glDeleteShader(stages[i]);
    GLint status = 0;
    glGetProgramiv(prog->id, GL_LINK_STATUS, &status);
    if (!status) {
        char log[4096];
        glGetProgramInfoLog(prog->id, sizeof(log), NULL, log);
        log_error("shaders/%s: link failed: %s", name, log);
        glDeleteProgram(prog->id);
        prog->id = 0;
        return false;
    }
    return true;
}

bool gpu_program_init(struct gpu_program *prog, const char *name, const char *defines)
{
    memset(prog, 0, sizeof(*prog));
    GLuint sh = compile_stage(name, defines, GL_COMPUTE_SHADER);
    if (!sh || !link_program(prog, name, &sh, 1))
        return false;
    glGetProgramiv(prog->id, GL_COMPUTE_WORK_GROUP_SIZE, prog->local_size);
    return true;
}

bool gpu_program_init_graphics(struct gpu_program *prog, const char *vertex,
                               const char *fragment, const char *defines)
{
    memset(prog, 0, sizeof(*prog));
    GLuint st[2];
    st[0] = compile_stage(vertex, defines, GL_VERTEX_SHADER);
    if (!st[0])
        return false;
    st[1] = compile_stage(fragment, defines, GL_FRAGMENT_SHADER);
    if (!st[1]) {
        glDeleteShader(st[0]);
        return false;
    }
    return link_program(prog, fragment, st, 2);
}

void gpu_program_finish(struct gpu_program *prog)
{
    if (!prog || !prog->id)
        return;
    glDeleteProgram(prog->id);
    prog->id = 0;
}

void gpu_program_use(const struct gpu_program *prog)
{
    glUseProgram(prog->id);
}

void gpu_uniform_int(const struct gpu_program *p, const char *name, int v)
{
    glProgramUniform1i(p->id, glGetUniformLocation(p->id, name), v);
}

void gpu_uniform_float(const struct gpu_program *p, const char *name, float v)
{
    glProgramUniform1f(p->id, glGetUniformLocation(p->id, name), v);
}

void gpu_uniform_uint(const struct gpu_program *p, const char *name, unsigned v)
{
    glProgramUniform1ui(p->id, glGetUniformLocation(p->id, name), v);
}

void gpu_uniform_double(const struct gpu_program *p, const char *name, double v)
{
    glProgramUniform1d(p->id, glGetUniformLocation(p->id, name), v);
}

void gpu_uniform_vec2(const struct gpu_program *p, const char *name, const float v[2])
{
    glProgramUniform2fv(p->id, glGetUniformLocation(p->id, name), 1, v);
}

void gpu_uniform_vec3(const struct gpu_program *p, const char *name, const float v[3])
{
    glProgramUniform3fv(p->id, glGetUniformLocation(p->id, name), 1, v);
}

void gpu_uniform_ivec2(const struct gpu_program *p, const char *name, const int v[2])
{
    glProgramUniform2iv(p->id, glGetUniformLocation(p->id, name), 1, v);
}

void gpu_uniform_ivec3(const struct gpu_program *p, const char *name, const int v[3])
{
    glProgramUniform3iv(p->id, glGetUniformLocation(p->id, name), 1, v);
}

void gpu_uniform_ivec4_array(const struct gpu_program *p, const char *name, int count,
                             const int *v)
{
    glProgramUniform4iv(p->id, glGetUniformLocation(p->id, name), count, v);
}

void gpu_uniform_float_array(const struct gpu_program *p, const char *name, int count,
                             const float *v)
{
    glProgramUniform1fv(p->id, glGetUniformLocation(p->id, name), count, v);
}

void gpu_uniform_vec4(const struct gpu_program *p, const char *name, const float v[4])
{
    glProgramUniform4fv(p->id, glGetUniformLocation(p->id, name), 1, v);
}

void gpu_uniform_mat4(const struct gpu_program *p, const char *name, const float m[16])
{
    glProgramUniformMatrix4fv(p->id, glGetUniformLocation(p->id, name), 1, GL_FALSE, m);
}

/* After a dispatch: its writes are seen by what follows, an indirect dispatch's arguments
 * included. */
static void dispatch_barrier(void)
{
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                    GL_SHADER_STORAGE_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT |
                    GL_BUFFER_UPDATE_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT |
                    GL_COMMAND_BARRIER_BIT);
}

void gpu_dispatch(const struct gpu_program *prog, int w, int h, int d)
{
    glUseProgram(prog->id);
    GLuint gx = (GLuint)((w + prog->local_size[0] - 1) / prog->local_size[0]);
    GLuint gy = (GLuint)((h + prog->local_size[1] - 1) / prog->local_size[1]);
    GLuint gz = (GLuint)((d + prog->local_size[2] - 1) / prog->local_size[2]);
    glDispatchCompute(gx, gy, gz);
    dispatch_barrier();
}

void gpu_dispatch_indirect(const struct gpu_program *prog, const struct gpu_buffer *args,
                           size_t offset)
{
    glUseProgram(prog->id);
    glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, args->id);
    glDispatchComputeIndirect((GLintptr)offset);
    glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
    dispatch_barrier();
}

void gpu_finish(void)
{
    glFinish();
}

/* ---- presenting ---------------------------------------------------------------------- */

void gpu_present(const struct gpu_texture *tex, int x, int y, int w, int h, int buffer)
{
    GLuint fbo;
    glCreateFramebuffers(1, &fbo);
    glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, tex->id, 0);
    GLenum target = buffer == 1 ? GL_BACK_LEFT : buffer == 2 ? GL_BACK_RIGHT : GL_BACK;
    glNamedFramebufferDrawBuffer(0, target);
    glBlitNamedFramebuffer(fbo, 0, 0, 0, tex->size[0], tex->size[1], x, y, x + w, y + h,
                           GL_COLOR_BUFFER_BIT, GL_LINEAR);
    glDeleteFramebuffers(1, &fbo);
}

void gpu_clear_default(float r, float g, float b)
{
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glClearColor(r, g, b, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
}

/* ---- timers -------------------------------------------------------------------------- */

void gpu_timings_add(struct gpu_timings *log, unsigned number, double ms)
{
    assert(number >= 1 && number <= log->count);
    if (number <= GPU_TIMINGS_KEPT)
        log->ms[number - 1] += ms;
    log->total_ms += ms;
}

/* Measurement NUMBER of LOG took MS on the GPU. */
static void arrive(struct gpu_timer_queue *q, struct gpu_timings *log, unsigned number,
                   double ms)
{
    gpu_timings_add(log, number, ms);
    if (number <= GPU_TIMINGS_KEPT)
        log->known[number - 1] = true;
    log->arrived++;
    q->last_ms = ms;
}

/* Drivers that run compute work on the calling thread, whose timestamps do not advance
 * across it. */
bool gpu_software_driver(void)
{
    const char *name = (const char *)glGetString(GL_RENDERER);
    return name && (strstr(name, "llvmpipe") || strstr(name, "softpipe"));
}

bool gpu_has_extension(const char *name)
{
    return epoxy_has_gl_extension(name);
}

void gpu_timer_queue_init(struct gpu_timer_queue *q, enum gpu_timer_clock clock)
{
    memset(q, 0, sizeof(*q));
    q->wall_clock = clock == GPU_TIMER_WALL || (clock == GPU_TIMER_AUTO && gpu_software_driver());
    if (q->wall_clock)
        return;
    for (int i = 0; i < GPU_TIMER_QUEUE_SIZE; i++)
        glGenQueries(2, q->slot[i].query);
}

void gpu_timer_queue_finish(struct gpu_timer_queue *q)
{
    if (!q)
        return;
    for (int i = 0; i < GPU_TIMER_QUEUE_SIZE; i++) {
        if (q->slot[i].query[0])
            glDeleteQueries(2, q->slot[i].query);
    }
    memset(q, 0, sizeof(*q));
}

/* Reads the oldest measurement in flight into its log: false (nothing read) when the GPU has
 * not passed its end yet and WAIT is false. */
static bool collect_oldest(struct gpu_timer_queue *q, bool wait)
{
    struct gpu_timer_slot *s = &q->slot[q->head];
    if (!wait) {
        GLint ready = 0;
        glGetQueryObjectiv(s->query[1], GL_QUERY_RESULT_AVAILABLE, &ready);
        if (!ready)
            return false;
    }
    /* Available (or waited for): the first timestamp came before the second. */
    GLuint64 a = 0, b = 0;
    glGetQueryObjectui64v(s->query[0], GL_QUERY_RESULT, &a);
    glGetQueryObjectui64v(s->query[1], GL_QUERY_RESULT, &b);
    arrive(q, s->log, s->number, b > a ? (double)(b - a) * 1e-6 : 0.0);
    q->head = (q->head + 1) % GPU_TIMER_QUEUE_SIZE;
    q->pending--;
    return true;
}

void gpu_timer_queue_begin(struct gpu_timer_queue *q)
{
    q->running = true;
    if (q->wall_clock) {
        q->cpu_start = time_now_ms();
        return;
    }
    if (q->pending == GPU_TIMER_QUEUE_SIZE)
        collect_oldest(q, true);
    int next = (q->head + q->pending) % GPU_TIMER_QUEUE_SIZE;
    glQueryCounter(q->slot[next].query[0], GL_TIMESTAMP);
}

unsigned gpu_timer_queue_end(struct gpu_timer_queue *q, struct gpu_timings *log)
{
    if (!q->running)
        return 0;
    q->running = false;
    unsigned number = ++log->count;
    if (q->wall_clock) {
        glFinish();
        arrive(q, log, number, time_now_ms() - q->cpu_start);
        return number;
    }
    struct gpu_timer_slot *s = &q->slot[(q->head + q->pending) % GPU_TIMER_QUEUE_SIZE];
    glQueryCounter(s->query[1], GL_TIMESTAMP);
    s->log = log;
    s->number = number;
    q->pending++;
    return number;
}

int gpu_timer_queue_collect(struct gpu_timer_queue *q, bool wait)
{
    while (q->pending > 0 && collect_oldest(q, wait)) {
    }
    return q->pending;
}
