// Primary rays of a pinhole camera.  Pixel (0, 0) is the top-left corner of the image.
#ifndef LS_CAMERA_H
#define LS_CAMERA_H

#include "float_bits.h"
#include "layouts.h"

#ifdef __cplusplus
namespace lsk {
#endif

// (px, py): a continuous position on the image, in pixels.
LS_FN Ray camera_ray(IN(CameraFrame) cam, float px, float py) {
  precise float sx = (2.0f * px / float(cam.width) - 1.0f) * cam.tan_half_fov * cam.aspect;
  precise float sy = (1.0f - 2.0f * py / float(cam.height)) * cam.tan_half_fov;
  precise vec3 d = cam.forward + cam.right * sx + cam.up * sy;
  Ray r;
  r.origin = cam.position;
  r.tmin = 0.0f;
  r.dir = normalize_in_order(d);
  r.tmax = ls_infinity();
  return r;
}

#ifdef __cplusplus
}  // namespace lsk
#endif

#endif
