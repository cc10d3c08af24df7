/* An animation: frame after frame through the session, each written. */
#include "session/animation.h"

#include <math.h>

#include "common/progress.h"
#include "session/camera_path.h"

long animation_frames(const struct animation_desc *a)
{
    if (a->path)
        return (long)(a->last - a->first) + 1;
    return a->by > 0.0 ? (long)floor((a->last - a->first) / a->by + 1e-9) + 1 : 1;
}

void animation_set_frame(struct session *s, const struct animation_desc *a, long i,
                         const struct display_camera *base)
{
    if (!a->path) {
        session_set_time(s, a->first + (double)i * a->by);
        return;
    }
    struct display_camera cam;
    double step = -1.0;
    camera_path_eval(a->path, (a->first + (double)i) / a->fps, base, &cam, &step);
    session_set_camera(s, &cam);
    if (step >= 0.0)
        session_set_time(s, step);
}

static bool frame(struct display *d, struct session *s, double time)
{
    struct frame_state f;
    bool redraw;
    return session_update(s, NULL, 0.0, time, &f, &redraw) && session_apply(s, &f, NULL) &&
           session_light(s) && display_sample_head(d, f.time_s, &f.head) &&
           session_draw(s, d, &f);
}

bool animation_run(struct display *d, struct session *s, const struct animation_desc *a,
                   struct frame_output *out)
{
    long count = animation_frames(a);
    struct frame_state f;
    bool redraw;
    if (!session_update(s, NULL, 0.0, a->time, &f, &redraw))
        return false;
    struct display_camera base = f.camera;
    struct progress pr;
    progress_begin(&pr, "render", "frame", (uint64_t)count);
    bool ok = true;
    for (long i = 0; ok && i < count; i++) {
        animation_set_frame(s, a, i, &base);
        ok = frame(d, s, a->time) && (!out || frame_output_add(out, d, (int)i));
        progress_update(&pr, (uint64_t)i + 1);
    }
    progress_end(&pr);
    return ok;
}
