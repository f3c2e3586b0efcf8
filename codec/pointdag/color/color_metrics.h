// Color quality over voxels: PSNR of RGB (all channels pooled) and of luma Y (BT.709 weights), with
// 255 as the peak, as MPEG's pc_error reports it for attributes.
#pragma once

#include <span>

#include "pointdag/voxelize/voxelizer.h"

namespace pointdag {

struct ColorPsnr {
  double rgb = 0;  // dB; infinity when identical
  double y = 0;
  double mse_rgb = 0;
  double mse_y = 0;
};

inline double LumaBt709(const Rgb8& c) { return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b; }

// `a` and `b` must have the same length.
ColorPsnr MeasureColorPsnr(std::span<const Rgb8> a, std::span<const Rgb8> b);

double PsnrFromMse(double mse, double peak = 255.0);

}  // namespace pointdag
