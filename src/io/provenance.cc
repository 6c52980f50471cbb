// The "data" block of result documents (provenance.h).
#include "ctid/io/provenance.h"

#include "ctid/core/fields.h"
#include "ctid/io/fields_json.h"

namespace ctid::io {

nlohmann::json to_json(const DataProvenance& provenance) {
  nlohmann::json block = nlohmann::json::object();
  if (!provenance.files.empty()) block["file"] = provenance.files.front();
  if (provenance.files.size() > 1) block["files"] = provenance.files;
  if (provenance.samples) block["samples"] = *provenance.samples;
  if (!provenance.record_samples.empty()) block["record_samples"] = provenance.record_samples;
  if (provenance.sample_time) block["sample_time"] = *provenance.sample_time;
  if (provenance.start_time) block["start_time"] = *provenance.start_time;
  if (provenance.lines) block["lines"] = *provenance.lines;
  if (provenance.inputs) block["inputs"] = *provenance.inputs;
  if (provenance.outputs) block["outputs"] = *provenance.outputs;
  if (provenance.input_hold) block["input_hold"] = enum_name(*provenance.input_hold);
  if (provenance.preprocessing) block["preprocessing"] = fields_to_json(*provenance.preprocessing);
  if (provenance.duplicate_stamps) {
    block["time_stamps"] = "irregular";
    block["duplicate_stamps"] = *provenance.duplicate_stamps;
  }
  if (provenance.detrend) block["detrend"] = *provenance.detrend;
  return block;
}

}  // namespace ctid::io
