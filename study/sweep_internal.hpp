#pragma once
// What the files of the sweep share and nothing else uses: the sweep file's reader (sweep_file.cpp),
// the run table (sweep_table.cpp), the sweep folder (sweep_folder.cpp) and the engine (sweep.cpp).
// Their API is study/sweep.hpp; their refusals are core's (core/input_document.hpp).
#include <nlohmann/json.hpp>
#include <string_view>

#include "core/run_config.hpp"

namespace confpack::study {

// The run configuration of a sweep file's base: its keys over the defaults, each one checked (an
// unknown key is a typo, refused by its path), and read as config.json is.
core::RunConfig resolveBase(const nlohmann::json& given, std::string_view source);

}  // namespace confpack::study
