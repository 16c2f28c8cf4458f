// gen_config_reference: prints docs/configuration.md from the key registry, writes it (target
// docs-config), or checks the committed page against it (the CTest test
// Docs.ConfigurationReferenceIsCurrent).
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include "config/KeyReference.hpp"

namespace {

namespace fs = std::filesystem;
using rovermap::config::FindPresets;
using rovermap::config::WriteKeyReference;

constexpr const char* kUsage =
    "usage: gen_config_reference --source DIR [--write FILE | --check FILE [--build-dir DIR]]\n"
    "  prints the configuration reference (presets from DIR/config/presets), or writes it to\n"
    "  FILE, or exits 1 naming the first line where FILE differs from it\n";

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream stream(text);
  for (std::string line; std::getline(stream, line);) lines.push_back(line);
  return lines;
}

// 0 if `file` holds exactly `generated`; else 1, with the first differing line on stderr.
int Check(const fs::path& file, const std::string& generated, const std::string& build_dir) {
  const std::string fix =
      "run cmake --build " + build_dir + " --target docs-config to regenerate it, then commit it\n";
  std::ifstream stream(file, std::ios::binary);
  if (!stream) {
    std::cerr << file.string() << ": missing or unreadable; " << fix;
    return 1;
  }
  std::ostringstream committed;
  committed << stream.rdbuf();
  if (committed.str() == generated) return 0;

  const std::vector<std::string> old_lines = Lines(committed.str());
  const std::vector<std::string> new_lines = Lines(generated);
  std::size_t line = 0;
  while (line < old_lines.size() && line < new_lines.size() && old_lines[line] == new_lines[line])
    ++line;
  auto at = [line](const std::vector<std::string>& lines) {
    return line < lines.size() ? lines[line] : std::string("(end of file)");
  };
  std::cerr << file.string() << ":" << line + 1
            << ": differs from what the key registry gives (first difference)\n"
            << "- " << at(old_lines) << "\n"
            << "+ " << at(new_lines) << "\n"
            << (line == old_lines.size() && line == new_lines.size()
                    ? "(the files differ only in their line endings or final newline)\n"
                    : "")
            << fix;
  return 1;
}

// Writes through a temporary file, so an interrupted run leaves the old page whole.
void Write(const fs::path& file, const std::string& text) {
  if (file.has_parent_path()) fs::create_directories(file.parent_path());
  const fs::path temporary = file.string() + ".tmp";
  {
    std::ofstream stream(temporary, std::ios::binary | std::ios::trunc);
    stream << text;
    stream.close();
    if (!stream) throw std::runtime_error(temporary.string() + ": cannot write");
  }
  fs::rename(temporary, file);
}

}  // namespace

int main(int argc, char** argv) {
  fs::path source;
  fs::path write_file;
  fs::path check_file;
  std::string build_dir = "BUILD";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--source" && has_value) {
      source = argv[++i];
    } else if (arg == "--write" && has_value) {
      write_file = argv[++i];
    } else if (arg == "--check" && has_value) {
      check_file = argv[++i];
    } else if (arg == "--build-dir" && has_value) {
      build_dir = argv[++i];
    } else {
      std::cerr << kUsage;
      return 2;
    }
  }
  if (source.empty() || (!write_file.empty() && !check_file.empty())) {
    std::cerr << kUsage;
    return 2;
  }
  try {
    std::ostringstream page;
    WriteKeyReference(page, FindPresets(source));
    if (!check_file.empty()) return Check(check_file, page.str(), build_dir);
    if (!write_file.empty()) {
      Write(write_file, page.str());
    } else {
      std::cout << page.str();
    }
  } catch (const std::exception& e) {
    std::cerr << "gen_config_reference: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
