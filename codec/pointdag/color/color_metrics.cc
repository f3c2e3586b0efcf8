#include "pointdag/color/color_metrics.h"

#include <cmath>
#include <limits>

#include "pointdag/color/block_fit.h"

namespace pointdag {

double PsnrFromMse(double mse, double peak) {
  if (mse <= 0) return std::numeric_limits<double>::infinity();
  return 10.0 * std::log10(peak * peak / mse);
}

ColorPsnr MeasureColorPsnr(std::span<const Rgb8> a, std::span<const Rgb8> b) {
  ColorPsnr out;
  if (a.empty()) return {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(), 0, 0};
  double sse = 0, sse_y = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    sse += SquaredError(a[i], b[i]);
    const double dy = LumaBt709(a[i]) - LumaBt709(b[i]);
    sse_y += dy * dy;
  }
  out.mse_rgb = sse / (3.0 * static_cast<double>(a.size()));
  out.mse_y = sse_y / static_cast<double>(a.size());
  out.rgb = PsnrFromMse(out.mse_rgb);
  out.y = PsnrFromMse(out.mse_y);
  return out;
}

}  // namespace pointdag
