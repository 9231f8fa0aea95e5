/* See camera.h. */
#include "camera.h"

#include <math.h>

static void sub3(const float a[3], const float b[3], float o[3])
{
    for (int k = 0; k < 3; ++k)
        o[k] = a[k] - b[k];
}

static void norm3(float v[3])
{
    float l = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (l > 0)
        for (int k = 0; k < 3; ++k)
            v[k] /= l;
}

static void cross3(const float a[3], const float b[3], float o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

void sr_camera_frame(const sr_camera *cam, unsigned width, unsigned height, rt_frame *f)
{
    float fwd[3], right[3], up[3];
    sub3(cam->look_at, cam->eye, fwd);
    norm3(fwd);
    cross3(fwd, cam->up, right);
    norm3(right);
    cross3(right, fwd, up);
    float hh = tanf(cam->vfov * 0.5f * 3.14159265358979f / 180.0f);
    float hw = hh * (float)width / (float)height;
    for (int k = 0; k < 3; ++k) {
        f->eye[k] = cam->eye[k];
        f->corner[k] = fwd[k] - right[k] * hw + up[k] * hh;
        f->du[k] = right[k] * (2.0f * hw / (float)width);
        f->dv[k] = -up[k] * (2.0f * hh / (float)height);
    }
    f->width = width;
    f->height = height;
}
