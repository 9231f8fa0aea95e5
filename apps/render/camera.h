/*
 * The pinhole camera on the device: the frame from which kernels/render/
 * camera.cl makes eye rays (Purcell Fig. 3.1's first kernel), shared by the
 * renderers.
 */
#ifndef SR_CAMERA_H
#define SR_CAMERA_H

#include "../../kernels/render/rt_types.h"
#include "scene.h"

/** Fills the camera part of `f` (eye, corner, du, dv, width, height) for
 *  `cam` seen at width x height; the other fields are left as they are. */
void sr_camera_frame(const sr_camera *cam, unsigned width, unsigned height, rt_frame *f);

#endif /* SR_CAMERA_H */
