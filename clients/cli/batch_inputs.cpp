#include "batch_inputs.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <system_error>

namespace rdmesh::cli {

namespace fs = std::filesystem;

namespace {

// An input before its output name is chosen: the path it mirrors, relative to its root.
struct Found {
  fs::path path;
  fs::path mirrored;
  bool listed = false;
};

fs::path Absolute(const fs::path& path) {
  std::error_code error;
  fs::path absolute = fs::absolute(path, error);
  fs::path normal = (error ? path : absolute).lexically_normal();
  // "out/" names the folder "out".
  return normal.has_filename() || normal == normal.root_path() ? normal : normal.parent_path();
}

std::string Lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

// Whether `path` lies at or below `folder` (both absolute and normal).
bool IsWithin(const fs::path& path, const fs::path& folder) {
  fs::path relative = path.lexically_relative(folder);
  return !relative.empty() && *relative.begin() != "..";
}

Status Refuse(const std::string& message) { return Status(StatusCode::kInvalidArgument, message); }

// Every model file below `folder`, sorted, mirrored relative to `root`.
Status Walk(const fs::path& folder, const fs::path& root, const fs::path& output_dir, bool listed,
            std::vector<Found>* found) {
  std::vector<Found> files;
  std::error_code error;
  fs::recursive_directory_iterator it(folder, fs::directory_options::skip_permission_denied, error);
  if (error) return Refuse("cannot read folder '" + folder.string() + "': " + error.message());
  for (; it != fs::recursive_directory_iterator(); it.increment(error)) {
    if (error) return Refuse("cannot walk '" + folder.string() + "': " + error.message());
    const fs::path path = it->path().lexically_normal();
    std::error_code type_error;
    if (it->is_directory(type_error)) {
      // The outputs of an earlier run inside the folder are not inputs.
      if (path == output_dir) it.disable_recursion_pending();
      continue;
    }
    if (!IsModelFile(path.string()) || !it->is_regular_file(type_error)) continue;
    files.push_back({path, path.lexically_relative(root), listed});
  }
  std::sort(files.begin(), files.end(),
            [](const Found& a, const Found& b) { return a.mirrored < b.mirrored; });
  found->insert(found->end(), files.begin(), files.end());
  return Status::Ok();
}

// The deepest folder holding every one of `paths` (absolute and normal).
fs::path CommonFolder(const std::vector<fs::path>& paths) {
  fs::path common;
  bool first = true;
  for (const fs::path& path : paths) {
    if (first) {
      common = path;
      first = false;
      continue;
    }
    fs::path shared;
    auto a = common.begin();
    auto b = path.begin();
    for (; a != common.end() && b != path.end() && *a == *b; ++a, ++b) shared /= *a;
    common = shared;
  }
  return common;
}

Status ReadList(const std::string& list, const fs::path& output_dir, std::vector<Found>* found) {
  std::ifstream in(list);
  if (!in) return Refuse("cannot read the list '" + list + "'");
  const fs::path folder = Absolute(list).parent_path();
  std::vector<fs::path> entries;
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const size_t start = line.find_first_not_of(" \t");
    if (start == std::string::npos || line[start] == '#') continue;
    const size_t end = line.find_last_not_of(" \t");
    fs::path entry(line.substr(start, end - start + 1));
    entries.push_back(Absolute(entry.is_absolute() ? entry : folder / entry));
  }
  if (in.bad()) return Refuse("cannot read the list '" + list + "'");
  // Mirror relative to the list's folder, or to what holds every entry when some lie outside.
  fs::path root = folder;
  std::vector<fs::path> homes;
  bool outside = false;
  for (const fs::path& entry : entries) {
    std::error_code error;
    const bool folder_entry = fs::is_directory(entry, error);
    homes.push_back(folder_entry ? entry : entry.parent_path());
    outside = outside || !IsWithin(entry, folder);
  }
  if (outside) root = CommonFolder(homes);
  for (const fs::path& entry : entries) {
    std::error_code error;
    if (fs::is_directory(entry, error)) {
      Status walked = Walk(entry, root, output_dir, true, found);
      if (!walked.ok()) return walked;
    } else {
      // A missing entry stays: the run reports it as unreadable.
      found->push_back({entry, entry.lexically_relative(root), true});
    }
  }
  return Status::Ok();
}

std::string OutputName(const fs::path& mirrored, const std::string& extension, bool keep) {
  fs::path output = mirrored;
  if (keep)
    output += extension;
  else
    output.replace_extension(extension);
  return output.generic_string();
}

}  // namespace

bool IsModelFile(const std::string& path) {
  static const std::set<std::string> kExtensions = {".step", ".stp", ".iges", ".igs", ".brep"};
  return kExtensions.count(Lower(fs::path(path).extension().string())) > 0;
}

Result<std::vector<BatchInput>> CollectInputs(const std::vector<std::string>& args,
                                              const std::string& extension,
                                              const std::string& output_dir) {
  const fs::path out = Absolute(output_dir);
  std::vector<Found> found;
  for (const std::string& arg : args) {
    Status status = Status::Ok();
    if (arg.size() > 1 && arg[0] == '@') {
      status = ReadList(arg.substr(1), out, &found);
    } else {
      std::error_code error;
      const fs::path path = Absolute(arg);
      const fs::file_status type = fs::status(path, error);
      if (fs::is_directory(type))
        status = Walk(path, path, out, false, &found);
      else if (fs::exists(type))
        found.push_back({path, path.filename(), false});
      else
        status = Refuse("no such file or folder: '" + arg + "'");
    }
    if (!status.ok()) return status;
  }

  // A file named twice counts once.
  std::vector<Found> unique;
  std::set<fs::path> seen;
  for (Found& f : found)
    if (seen.insert(f.path).second) unique.push_back(std::move(f));
  if (unique.empty()) return Refuse("no model files (.step .stp .iges .igs .brep) in the inputs");

  // Outputs: the extension replaced; where that collides, kept before the new one.
  std::map<std::string, std::vector<size_t>> by_output;
  for (size_t i = 0; i < unique.size(); ++i)
    by_output[OutputName(unique[i].mirrored, extension, false)].push_back(i);
  std::vector<BatchInput> inputs(unique.size());
  for (const auto& [output, users] : by_output) {
    // Keeping the extension helps only inputs whose mirrored paths differ (a.step, a.stp).
    std::set<fs::path> mirrored;
    for (size_t i : users) mirrored.insert(unique[i].mirrored);
    const bool keep = users.size() > 1 && mirrored.size() == users.size();
    for (size_t i : users)
      inputs[i] = {unique[i].path.string(), OutputName(unique[i].mirrored, extension, keep),
                   unique[i].listed};
  }
  std::map<std::string, size_t> owner;
  for (size_t i = 0; i < inputs.size(); ++i) {
    const std::string& output = inputs[i].output;
    if (output.empty() || output.rfind("../", 0) == 0 || fs::path(output).is_absolute())
      return Refuse("cannot place the output of '" + inputs[i].path + "' under the output folder");
    auto [it, added] = owner.emplace(output, i);
    if (!added)
      return Refuse("'" + inputs[it->second].path + "' and '" + inputs[i].path +
                    "' would both write '" + output +
                    "': mesh them into separate output folders, or list them from one folder");
  }
  return inputs;
}

}  // namespace rdmesh::cli
