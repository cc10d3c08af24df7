/* Animation frames to numbered images or movies, one stream per view and per stereo pair. */
#include "session/output.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "common/log.h"
#include "render/image.h"
#include "render/video.h"

#define STREAMS_MAX (DISPLAY_MAX_VIEWS + DISPLAY_MAX_WALLS)
#define NAME_MAX_LEN 1200

struct stream {
    char name[48]; /* the view's or the wall's ("" for the one view) */
    struct video_writer *video;
};

struct frame_output {
    struct frame_output_desc d;
    char path[1024];
    char codec[64];
    bool movie;
    struct stream streams[STREAMS_MAX];
    int n_streams;
    int frames;
};

/* The integer conversion of PATH ("%05d"): its start and length, or false.  "%%" is a '%',
 * "%v" the view's name. */
static bool find_number(const char *path, const char **at, size_t *len, int *count)
{
    *count = 0;
    *at = NULL;
    for (const char *p = path; *p; p++) {
        if (*p != '%')
            continue;
        const char *q = p + 1;
        if (*q == '%' || *q == 'v') {
            p = q;
            continue;
        }
        while (*q >= '0' && *q <= '9')
            q++;
        if (*q != 'd')
            return false;
        (*count)++;
        *at = p;
        *len = (size_t)(q - p + 1);
        p = q;
    }
    return *count == 1;
}

static bool folder_exists(const char *path, char *folder, size_t size)
{
    const char *slash = strrchr(path, '/');
    if (!slash)
        snprintf(folder, size, ".");
    else if (slash == path)
        snprintf(folder, size, "/");
    else
        snprintf(folder, size, "%.*s", (int)(slash - path), path);
    struct stat st;
    return stat(folder, &st) == 0 && S_ISDIR(st.st_mode);
}

/* The message for PATH whose folder FOLDER is not a folder. */
static void folder_missing(const char *path, const char *folder)
{
    struct stat st;
    if (stat(folder, &st) == 0)
        log_error("%s: %s is not a folder", path, folder);
    else
        log_error("%s: the folder %s does not exist (make it first)", path, folder);
}

bool frame_output_folder_exists(const char *path)
{
    char folder[1024];
    if (folder_exists(path, folder, sizeof(folder)))
        return true;
    folder_missing(path, folder);
    return false;
}

bool frame_output_check(const char *path)
{
    char folder[1024];
    if (strchr(path, '/') && strstr(strrchr(path, '/'), "%v") == NULL && strstr(path, "%v")) {
        log_error("%s: \"%%v\" (the view's name) may stand in the file's name only, not in its "
                  "folder",
                  path);
        return false;
    }
    if (!folder_exists(path, folder, sizeof(folder))) {
        folder_missing(path, folder);
        return false;
    }
    if (video_path_supported(path)) {
        if (strchr(path, '%') && !strstr(path, "%v")) {
            log_error("%s: a movie is one file: no frame number in its name", path);
            return false;
        }
        return true;
    }
    const char *at;
    size_t len;
    int count;
    if (!find_number(path, &at, &len, &count) || !image_path_supported(path)) {
        log_error("%s: expected a movie (.mp4, .mkv, .mov, ...) or numbered images: a .png or "
                  ".pfm name with one frame number in it, like out/frame-%%05d.png",
                  path);
        return false;
    }
    return true;
}

/* PATH for stream NAME ("" for the one view): "%v" replaced, or NAME- before the file name;
 * "%%" kept for the frame number's printf (KEEP), else made one '%' (a movie's name). */
static void stream_path(const char *path, const char *name, bool keep, char *out, size_t size)
{
    char buf[NAME_MAX_LEN] = "";
    size_t n = 0;
    bool named = false;
    for (const char *p = path; *p && n + 1 < sizeof(buf); p++) {
        if (p[0] == '%' && p[1] == 'v') {
            n += (size_t)snprintf(buf + n, sizeof(buf) - n, "%s", name);
            named = true;
            p++;
        } else if (p[0] == '%' && p[1] == '%') {
            buf[n++] = '%';
            if (keep && n + 1 < sizeof(buf))
                buf[n++] = '%';
            p++;
        } else {
            buf[n++] = *p;
        }
    }
    buf[n < sizeof(buf) ? n : sizeof(buf) - 1] = '\0';
    if (named || !name[0]) {
        snprintf(out, size, "%s", buf);
        return;
    }
    const char *dot = strrchr(buf, '.');
    if (!keep && dot && !strchr(dot, '/')) { /* a movie: "cave.mp4" -> "cave-front.mp4" */
        snprintf(out, size, "%.*s-%s%s", (int)(dot - buf), buf, name, dot);
        return;
    }
    const char *slash = strrchr(buf, '/');
    const char *file = slash ? slash + 1 : buf;
    snprintf(out, size, "%.*s%s-%s", (int)(file - buf), buf, name, file);
}

struct frame_output *frame_output_open(const struct frame_output_desc *d)
{
    if (!frame_output_check(d->path))
        return NULL;
    struct frame_output *o = calloc(1, sizeof(*o));
    if (!o) {
        log_error("%s: out of memory", d->path);
        return NULL;
    }
    o->d = *d;
    snprintf(o->path, sizeof(o->path), "%s", d->path);
    o->d.path = o->path;
    if (d->codec) {
        snprintf(o->codec, sizeof(o->codec), "%s", d->codec);
        o->d.codec = o->codec;
    }
    o->movie = video_path_supported(d->path);
    return o;
}

static struct stream *stream_of(struct frame_output *o, const char *name)
{
    for (int i = 0; i < o->n_streams; i++)
        if (strcmp(o->streams[i].name, name) == 0)
            return &o->streams[i];
    if (o->n_streams == STREAMS_MAX)
        return NULL;
    struct stream *s = &o->streams[o->n_streams++];
    snprintf(s->name, sizeof(s->name), "%s", name);
    return s;
}

/* Writes IMG as frame NUMBER of stream NAME. */
static bool write_stream(struct frame_output *o, const char *name, const struct image *img,
                         int number)
{
    struct stream *s = stream_of(o, name);
    char path[NAME_MAX_LEN];
    stream_path(o->path, name, !o->movie, path, sizeof(path));
    if (!s) {
        log_error("%s: too many views", o->path);
        return false;
    }
    if (o->movie) {
        if (!s->video) {
            s->video = video_open(path, &(struct video_desc){.width = img->width,
                                                             .height = img->height,
                                                             .fps = o->d.fps,
                                                             .codec = o->d.codec});
            if (!s->video)
                return false;
        }
        return video_add_frame(s->video, img, o->d.exposure);
    }
    char file[NAME_MAX_LEN + 32];
    snprintf(file, sizeof(file), path, number); /* the one integer conversion, checked */
    return image_write(img, file, o->d.exposure);
}

bool frame_output_add(struct frame_output *o, struct display *d, int number)
{
    int n = display_view_count(d);
    struct image images[DISPLAY_MAX_VIEWS];
    memset(images, 0, sizeof(images));
    bool ok = true;
    for (int i = 0; i < n && ok; i++) {
        const struct view *v = display_view(d, i);
        if (!v->target.id) {
            /* An eye behind its wall: black, so every stream keeps its frame count. */
            ok = image_init(&images[i], v->rv.width, v->rv.height);
            if (ok)
                memset(images[i].rgba, 0, sizeof(float) * 4 * (size_t)v->rv.width *
                                              (size_t)v->rv.height);
        } else {
            ok = renderer_read(&v->target, &images[i]);
        }
        if (ok)
            ok = write_stream(o, o->d.per_view ? v->name : "", &images[i], number);
        if (!o->d.per_view)
            break;
    }
    /* Stereo walls: the two eyes side by side. */
    for (int i = 0; ok && o->d.per_view && i < n; i++) {
        const struct view *l = display_view(d, i);
        if (l->eye != VIEW_EYE_LEFT)
            continue;
        for (int j = 0; j < n; j++) {
            const struct view *r = display_view(d, j);
            if (r->eye != VIEW_EYE_RIGHT || r->wall != l->wall || !images[i].rgba ||
                !images[j].rgba || images[i].height != images[j].height)
                continue;
            struct image pair;
            ok = image_init(&pair, images[i].width + images[j].width, images[i].height);
            if (!ok)
                break;
            image_blit(&pair, &images[i], 0, 0);
            image_blit(&pair, &images[j], images[i].width, 0);
            char name[48];
            snprintf(name, sizeof(name), "%s", l->name);
            char *dash = strrchr(name, '-'); /* "front-left" -> "front" */
            if (dash)
                *dash = '\0';
            ok = write_stream(o, name, &pair, number);
            image_finish(&pair);
        }
    }
    for (int i = 0; i < n; i++)
        image_finish(&images[i]);
    if (ok)
        o->frames++;
    return ok;
}

int frame_output_frames(const struct frame_output *o)
{
    return o->frames;
}

bool frame_output_close(struct frame_output *o)
{
    if (!o)
        return false;
    bool ok = true;
    for (int i = 0; i < o->n_streams; i++)
        if (o->streams[i].video)
            ok = video_close(o->streams[i].video) && ok;
    if (ok && !o->movie)
        log_info("wrote %d frames: %s", o->frames, o->path);
    free(o);
    return ok;
}

void frame_output_abort(struct frame_output *o)
{
    if (!o)
        return;
    for (int i = 0; i < o->n_streams; i++)
        video_abort(o->streams[i].video);
    free(o);
}
