#include "shadow_input.h"

#include <chrono>

#include "pointdag/container/json_fields.h"
#include "pointdag/pipeline.h"

namespace pointdag {
namespace {

// The ENU origin of a georeferenced .pdag (metadata "frame", written by encode --georeference and
// by pointdagd); a file without one is in its own frame.
Status ReadFrame(const nlohmann::json& meta, ShadowInput& out) {
  const JsonFields fields(meta, ".pdag metadata");
  const nlohmann::json* georeferenced = fields.Find("frame/georeferenced");
  if (georeferenced == nullptr || !georeferenced->is_boolean() || !georeferenced->get<bool>()) return Status::Ok();
  ASSIGN_OR_RETURN(out.latitude_deg, fields.Number("frame/enu_origin/lat"));
  ASSIGN_OR_RETURN(out.longitude_deg, fields.Number("frame/enu_origin/lon"));
  out.georeferenced = true;
  return Status::Ok();
}

}  // namespace

StatusOr<ShadowInput> LoadShadowInput(const std::filesystem::path& path, std::optional<double> voxel_size,
                                      std::optional<int> depth) {
  const auto start = std::chrono::steady_clock::now();
  ShadowInput out;
  if (path.extension() == ".pdag") {
    if (voxel_size || depth) return InvalidArgument("a .pdag has its own grid; --voxel and --depth are for scans");
    ASSIGN_OR_RETURN(PdagFile file, ReadPdag(path));
    ASSIGN_OR_RETURN(DecodedPdag decoded, DecodePdag(file));
    RETURN_IF_ERROR(ReadFrame(file.meta, out));
    out.grid = std::move(decoded.grid);
    out.dag = std::move(decoded.dag);
  } else {
    if (voxel_size.has_value() == depth.has_value()) return InvalidArgument("give a scan --voxel SIZE or --depth D");
    EncodeOptions options;
    options.voxel_size = voxel_size;
    options.depth = depth;
    options.georeference = true;
    options.colors = {ColorCodec::kRaw, std::nullopt};  // the colors are only passed through to -o OUT.ply
    ASSIGN_OR_RETURN(EncodedScan encoded, EncodeScan(path, options));
    out.georeferenced = encoded.frame.georeferenced;
    out.latitude_deg = encoded.frame.origin_llh[0];
    out.longitude_deg = encoded.frame.origin_llh[1];
    out.grid = std::move(encoded.grid);
    out.dag = std::move(encoded.dag);
  }
  out.load_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace pointdag
