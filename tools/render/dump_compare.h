// --compare-with DIR: the effect images of this run's --dump against those of an earlier dump of the same size and
// camera (the unbudgeted preset, for the frame budget's speed against error): per image, the RMSE over every pixel
// and channel and that RMSE over the reference's RMS. Images missing from either side are left out.
#pragma once

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

namespace rbRender {

// {"reference": DIR, "images": {"shadow": {"rmse", "relative_rmse"}, ...}}, or an error naming the file and why.
nlohmann::json compareDumps(const std::filesystem::path& reference, const std::filesystem::path& test,
                            std::string& error);

}  // namespace rbRender
