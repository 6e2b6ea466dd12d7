#include "sim/sumo_options.hpp"

#include <expat.h>
#include <fmt/format.h>

#include <cstring>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>

#include "sim/errors.hpp"
#include "sim/process.hpp"

namespace corridor::sim {
namespace {

struct TemplateParse {
  std::vector<std::string> stack;
  std::vector<std::pair<SumoOptionInfo, std::string>> options;  // with their synonyms
};

void on_template_start(void* user, const char* name, const char** attrs) {
  auto& st = *static_cast<TemplateParse*>(user);
  const char* value = nullptr;
  const char* synonyms = "";
  const char* type = "";
  for (const char** a = attrs; *a != nullptr; a += 2) {
    if (std::strcmp(a[0], "value") == 0) value = a[1];
    if (std::strcmp(a[0], "synonymes") == 0) synonyms = a[1];
    if (std::strcmp(a[0], "type") == 0) type = a[1];
  }
  if (value != nullptr) {
    st.options.push_back({{name, st.stack.empty() ? std::string{} : st.stack.back(), type}, synonyms});
  }
  st.stack.emplace_back(name);
}

void on_template_end(void* user, const char*) { static_cast<TemplateParse*>(user)->stack.pop_back(); }

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

}  // namespace

std::vector<std::string> split_files(const std::string& text) {
  std::vector<std::string> items;
  std::string item;
  for (std::size_t i = 0; i <= text.size(); ++i) {
    if (i == text.size() || text[i] == ',' || text[i] == ';') {
      const auto first = item.find_first_not_of(" \t\r\n");
      const auto last = item.find_last_not_of(" \t\r\n");
      if (first != std::string::npos) items.push_back(item.substr(first, last - first + 1));
      item.clear();
    } else {
      item += text[i];
    }
  }
  return items;
}

SumoOptionCatalog SumoOptionCatalog::from_template(const std::string& xml) {
  TemplateParse st;
  std::unique_ptr<XML_ParserStruct, decltype(&XML_ParserFree)> parser(XML_ParserCreate(nullptr), &XML_ParserFree);
  XML_SetUserData(parser.get(), &st);
  XML_SetElementHandler(parser.get(), on_template_start, on_template_end);
  if (XML_Parse(parser.get(), xml.data(), static_cast<int>(xml.size()), 1) == XML_STATUS_ERROR) {
    throw SimError(std::string("SUMO's option template is not XML: ") + XML_ErrorString(XML_GetErrorCode(parser.get())));
  }
  SumoOptionCatalog c;
  for (auto& [info, synonyms] : st.options) {
    const std::size_t index = c.options_.size();
    c.by_name_.emplace(info.name, index);
    std::istringstream in(synonyms);
    for (std::string s; in >> s;) c.by_name_.emplace(s, index);
    c.options_.push_back(std::move(info));
  }
  if (c.options_.size() < 10 || c.find("net-file") == nullptr) throw SimError("SUMO's option template lists no net-file option");
  return c;
}

SumoOptionCatalog SumoOptionCatalog::from_sumo(const std::string& binary, const std::filesystem::path& scratch_dir) {
  std::error_code ec;
  std::filesystem::create_directories(scratch_dir, ec);
  const auto file = scratch_dir / "sumo-options.template.xml";
  run_tool({binary, "--save-template", file.string()}, scratch_dir / "sumo-options.log");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw SimError("'" + binary + " --save-template' wrote no " + file.string());
  const std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return from_template(xml);
}

const SumoOptionInfo* SumoOptionCatalog::find(const std::string& name) const {
  const auto it = by_name_.find(name);
  return it == by_name_.end() ? nullptr : &options_[it->second];
}

bool SumoOptionCatalog::is_output(const SumoOptionInfo& o) const {
  return o.type == "FILE" && (o.section == "output" || o.name == "log" || o.name == "message-log" || o.name == "error-log");
}

void write_run_config(const std::filesystem::path& file, const SumoOptionCatalog& catalog,
                      const std::vector<SumoOptionValue>& user, const std::filesystem::path& user_dir,
                      const std::vector<std::pair<std::string, std::string>>& owned,
                      const std::function<std::string(const std::string&, const std::string&)>& redirect_output) {
  std::set<std::string> owned_names;
  for (const auto& [name, value] : owned) {
    const SumoOptionInfo* o = catalog.find(name);
    if (o == nullptr) throw SimError("Corridor sets SUMO option '" + name + "', which this SUMO does not have");
    owned_names.insert(o->name);
  }
  std::string body;
  std::set<std::string> written;
  for (const SumoOptionValue& v : user) {
    const SumoOptionInfo* o = catalog.find(v.name);
    if (o == nullptr) {
      throw SimError("the scenario's configuration sets '" + v.name + "', which is not an option of the installed SUMO");
    }
    // The last of two settings of one option is the one SUMO would keep; a derived file holds one.
    if (owned_names.contains(o->name)) continue;
    std::string value = v.value;
    if (o->type == "FILE" && !value.empty()) {
      if (catalog.is_output(*o)) {
        value = redirect_output(o->name, value);
      } else {
        // Relative to the user's configuration, as SUMO reads it there.
        std::string list;
        for (const auto& item : split_files(value)) {
          std::filesystem::path p(item);
          if (p.is_relative()) p = (user_dir / p).lexically_normal();
          list += (list.empty() ? "" : ",") + p.string();
        }
        value = list;
      }
    }
    if (!written.insert(o->name).second) {
      // Keep the later value: replace the earlier line.
      const std::string tag = "  <" + o->name + " value=";
      const auto at = body.find(tag);
      if (at != std::string::npos) body.erase(at, body.find('\n', at) - at + 1);
    }
    body += fmt::format("  <{} value=\"{}\"/>\n", o->name, xml_escape(value));
  }
  for (const auto& [name, value] : owned) body += fmt::format("  <{} value=\"{}\"/>\n", catalog.find(name)->name, xml_escape(value));
  std::ofstream out(file, std::ios::trunc | std::ios::binary);
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
         "<!-- Written by corridor for one run: the scenario's own options, with those the run owns set here. -->\n"
         "<configuration>\n"
      << body << "</configuration>\n";
  if (!out) throw SimError("cannot write the run's SUMO configuration " + file.string());
}

}  // namespace corridor::sim
