// SUMO's own option catalog (`sumo --save-template`: every option's name, synonyms, section and
// type), and the configuration a run writes into its work directory: the user's options as SUMO
// reads them, each resolved to its canonical name, with file options made absolute, and the
// options Corridor owns (network, demand, outputs, time window, seed, the run's log) set once.
// Handing SUMO the user's file plus command-line options collides wherever the file sets the same
// option (SUMO refuses a value set twice); a derived file cannot.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace corridor::sim {

struct SumoOptionInfo {
  std::string name;     // canonical
  std::string section;  // "input", "output", "report", ...
  std::string type;     // "FILE", "BOOL", "TIME", "STR[]", ...
};

class SumoOptionCatalog {
 public:
  // Runs `<binary> --save-template` into `scratch_dir`. Throws SimError when SUMO cannot write it.
  static SumoOptionCatalog from_sumo(const std::string& binary, const std::filesystem::path& scratch_dir);
  // From a template's XML text (tests). Throws SimError when it is not one.
  static SumoOptionCatalog from_template(const std::string& xml);

  // The option a name or synonym stands for, or nullopt when SUMO has no such option.
  [[nodiscard]] const SumoOptionInfo* find(const std::string& name) const;
  // Files the simulation writes (the output section, and the report's logs).
  [[nodiscard]] bool is_output(const SumoOptionInfo& o) const;
  [[nodiscard]] std::size_t size() const { return options_.size(); }

 private:
  std::vector<SumoOptionInfo> options_;
  std::unordered_map<std::string, std::size_t> by_name_;  // names and synonyms
};

// An option as a configuration file holds it: the element's name (maybe a synonym) and its value.
struct SumoOptionValue {
  std::string name;
  std::string value;
};

// The run's configuration file. `user` are the user's options in file order (empty for a generated
// scenario) and `user_dir` the directory their relative paths are relative to; `owned` are the
// options Corridor sets for the run, by canonical name, which replace any of the user's with the
// same meaning; `redirect_output` names where a user's output file goes instead of beside their
// files. Throws SimError for an option SUMO does not know (SUMO would refuse the file) and when the
// file cannot be written.
// A SUMO file list as SUMO reads it: separated by commas (or semicolons), each item trimmed, empty
// items dropped.
[[nodiscard]] std::vector<std::string> split_files(const std::string& text);

void write_run_config(const std::filesystem::path& file, const SumoOptionCatalog& catalog,
                      const std::vector<SumoOptionValue>& user, const std::filesystem::path& user_dir,
                      const std::vector<std::pair<std::string, std::string>>& owned,
                      const std::function<std::string(const std::string& option, const std::string& value)>& redirect_output);

}  // namespace corridor::sim
