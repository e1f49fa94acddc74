// The sweep folder as the study report reads it (study::loadStudy): one record per run of the
// table, for confpack.study.load (python/confpack/study.py), which makes the columns.
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "python/bindings.hpp"
#include "study/report.hpp"

namespace confpack::python {

void bindStudy(py::module_& m) {
  m.def(
      "_load_study",
      [](const std::filesystem::path& dir) {
        std::vector<study::RunRecord> records;
        {
          const py::gil_scoped_release release;
          records = study::loadStudy(dir);
        }
        py::list out;
        for (const study::RunRecord& r : records) {
          py::dict d;
          d["run"] = r.run.name;
          d["index"] = r.run.index;
          d["deposit"] = r.run.depositName();
          d["family"] = study::familyName(r.run.config);
          d["status"] = std::string(study::toString(r.status));
          d["config"] = nlohmann::json(r.run.config).dump();
          d["values"] = r.values;  // flattened numeric leaves of result.json, None where null
          d["result"] = r.result.is_null() ? std::string() : r.result.dump();
          const bool failed = r.marker.is_object() && r.marker.contains("error");
          d["error"] = failed ? r.marker.at("error").dump() : std::string();
          out.append(d);
        }
        return out;
      },
      "dir"_a, "The run table of a sweep folder with each run's status and result (study::loadStudy).");
}

}  // namespace confpack::python
