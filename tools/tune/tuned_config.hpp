// The rig's config with tuned gains: the text of the file with only the
// gain values of the top-level `controller:` section replaced, so comments,
// order and every other setting stay as they were (a YAML library would
// drop the comments). The result is loaded again and its gains checked.
#pragma once

#include <map>
#include <string>

namespace rigctl {

// Throws std::runtime_error naming the file when it has no `controller:`
// section or the edited text does not load with the new values.
std::string with_controller_values(const std::string& yaml_text, const std::map<std::string, double>& values,
                                   const std::string& name);

void write_tuned_config(const std::string& config_path, const std::string& out_path,
                        const std::map<std::string, double>& values);

}  // namespace rigctl
