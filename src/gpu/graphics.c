/* Meshes and offscreen render targets for the opaque geometry drawn before ray casting. */
#include <stdatomic.h>
#include <string.h>

#include <epoxy/gl.h>

#include "common/log.h"
#include "gpu/gpu.h"

bool gpu_mesh_init(struct gpu_mesh *mesh, const float *vertices, int vertex_count,
                   const int *attrib_sizes, int attrib_count, const uint32_t *indices,
                   int index_count, bool lines)
{
    memset(mesh, 0, sizeof(*mesh));
    int stride = 0;
    for (int i = 0; i < attrib_count; i++)
        stride += attrib_sizes[i];
    glCreateVertexArrays(1, &mesh->vao);
    glCreateBuffers(1, &mesh->vbo);
    glCreateBuffers(1, &mesh->ibo);
    size_t vbytes = (size_t)vertex_count * (size_t)stride * sizeof(float);
    size_t ibytes = (size_t)index_count * sizeof(uint32_t);
    while (glGetError() != GL_NO_ERROR) {
    }
    glNamedBufferStorage(mesh->vbo, (GLsizeiptr)(vbytes ? vbytes : 4), vertices, 0);
    glNamedBufferStorage(mesh->ibo, (GLsizeiptr)(ibytes ? ibytes : 4), indices, 0);
    if (glGetError() != GL_NO_ERROR) {
        log_error("the GPU could not allocate a mesh of %d vertices", vertex_count);
        gpu_mesh_finish(mesh);
        return false;
    }
    glVertexArrayVertexBuffer(mesh->vao, 0, mesh->vbo, 0, stride * (GLsizei)sizeof(float));
    glVertexArrayElementBuffer(mesh->vao, mesh->ibo);
    int offset = 0;
    for (int i = 0; i < attrib_count; i++) {
        glEnableVertexArrayAttrib(mesh->vao, (GLuint)i);
        glVertexArrayAttribFormat(mesh->vao, (GLuint)i, attrib_sizes[i], GL_FLOAT, GL_FALSE,
                                  (GLuint)(offset * (int)sizeof(float)));
        glVertexArrayAttribBinding(mesh->vao, (GLuint)i, 0);
        offset += attrib_sizes[i];
    }
    mesh->index_count = index_count;
    mesh->lines = lines;
    mesh->bytes = vbytes + ibytes;
    return true;
}

void gpu_mesh_finish(struct gpu_mesh *mesh)
{
    if (!mesh)
        return;
    if (mesh->vao)
        glDeleteVertexArrays(1, &mesh->vao);
    if (mesh->vbo)
        glDeleteBuffers(1, &mesh->vbo);
    if (mesh->ibo)
        glDeleteBuffers(1, &mesh->ibo);
    memset(mesh, 0, sizeof(*mesh));
}

void gpu_mesh_draw(const struct gpu_mesh *mesh, const struct gpu_program *prog)
{
    glUseProgram(prog->id);
    glBindVertexArray(mesh->vao);
    glDrawElements(mesh->lines ? GL_LINES : GL_TRIANGLES, mesh->index_count, GL_UNSIGNED_INT,
                   NULL);
    glBindVertexArray(0);
}

bool gpu_target_ensure(struct gpu_target *t, int width, int height)
{
    if (t->fbo && t->width == width && t->height == height)
        return true;
    gpu_target_finish(t);
    int size[3] = {width, height, 1};
    if (!gpu_texture_init(&t->color, 2, size, GPU_RGBA32F, NULL) ||
        !gpu_texture_init(&t->value, 2, size, GPU_R32F, NULL)) {
        gpu_target_finish(t);
        return false;
    }
    glTextureParameteri(t->color.id, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(t->color.id, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTextureParameteri(t->value.id, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(t->value.id, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glCreateRenderbuffers(1, &t->depth);
    glNamedRenderbufferStorage(t->depth, GL_DEPTH_COMPONENT32F, width, height);
    glCreateFramebuffers(1, &t->fbo);
    glNamedFramebufferTexture(t->fbo, GL_COLOR_ATTACHMENT0, t->color.id, 0);
    glNamedFramebufferTexture(t->fbo, GL_COLOR_ATTACHMENT1, t->value.id, 0);
    glNamedFramebufferRenderbuffer(t->fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t->depth);
    const GLenum bufs[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(t->fbo, 2, bufs);
    if (glCheckNamedFramebufferStatus(t->fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        log_error("the GPU cannot render to a %dx%d float target", width, height);
        gpu_target_finish(t);
        return false;
    }
    t->width = width;
    t->height = height;
    return true;
}

void gpu_target_finish(struct gpu_target *t)
{
    if (!t)
        return;
    if (t->fbo)
        glDeleteFramebuffers(1, &t->fbo);
    if (t->depth)
        glDeleteRenderbuffers(1, &t->depth);
    gpu_texture_finish(&t->color);
    gpu_texture_finish(&t->value);
    memset(t, 0, sizeof(*t));
}

void gpu_target_begin(struct gpu_target *t, const float clear_color[4], float clear_value)
{
    glBindFramebuffer(GL_FRAMEBUFFER, t->fbo);
    glViewport(0, 0, t->width, t->height);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_BLEND);
    glDisable(GL_CULL_FACE);
    glClearNamedFramebufferfv(t->fbo, GL_COLOR, 0, clear_color);
    const float value[4] = {clear_value, 0, 0, 0};
    glClearNamedFramebufferfv(t->fbo, GL_COLOR, 1, value);
    const float depth = 1.0f;
    glClearNamedFramebufferfv(t->fbo, GL_DEPTH, 0, &depth);
}

void gpu_target_end(struct gpu_target *t)
{
    (void)t;
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDisable(GL_DEPTH_TEST);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
}
