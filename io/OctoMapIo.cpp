#include "io/OctoMapIo.hpp"

#include <octomap/AbstractOcTree.h>

#include <array>
#include <cstdint>
#include <sstream>

#include "dem/OcTreeBytes.hpp"
#include "dem/QuietStderr.hpp"
#include "io/FileUtil.hpp"
#include "io/IoError.hpp"

namespace rovermap::io {

std::size_t CountSerialisedLeaves(std::string_view data, bool binary) {
  const std::size_t header_end = data.find("\ndata\n");
  if (header_end == std::string_view::npos) throw IoError("OcTree data without a 'data' line");
  const std::string_view body = data.substr(header_end + 6);
  std::size_t leaves = 0;
  if (binary) {
    // Per inner node, two bytes of 2-bit child codes: 1 free leaf, 2 occupied leaf, 3 inner,
    // 0 none (dem/OcTreeBytes).
    static const std::array<std::uint8_t, 256> kLeafCodes = [] {
      std::array<std::uint8_t, 256> t{};
      for (int b = 0; b < 256; ++b)
        for (int i = 0; i < 4; ++i) {
          const int code = (b >> (2 * i)) & 3;
          t[b] += code == 1 || code == 2 ? 1 : 0;
        }
      return t;
    }();
    for (const char c : body) leaves += kLeafCodes[static_cast<unsigned char>(c)];
    // A root without children is itself the one leaf (two bytes of 00).
    if (leaves == 0 && !body.empty()) leaves = 1;
  } else {
    // Per node in pre-order: its value (a float), then a byte with a bit per existing child.
    constexpr std::size_t kRecord = sizeof(float) + 1;
    for (std::size_t i = kRecord - 1; i < body.size(); i += kRecord) leaves += body[i] == 0 ? 1 : 0;
  }
  return leaves;
}

OctoMapFileInfo WriteOctoMap(const std::filesystem::path& path, const octomap::OcTree& tree) {
  const std::string ext = path.extension().string();
  if (ext != ".bt" && ext != ".ot") {
    throw IoError(path.string() + ": OctoMap files must end in .bt or .ot");
  }
  const std::string data = ext == ".bt" ? dem::BinaryOcTreeBytes(tree) : dem::FullOcTreeBytes(tree);
  WriteFileAtomically(path, data);
  return {data.size(), CountSerialisedLeaves(data, ext == ".bt")};
}

std::unique_ptr<octomap::OcTree> ReadOctoMap(const std::filesystem::path& path) {
  const std::string data = ReadWholeFile(path);
  const std::string ext = path.extension().string();
  // Check the header first: OctoMap prints its own complaints to stderr.
  const std::string header =
      ext == ".bt" ? "# Octomap OcTree binary file" : "# Octomap OcTree file";
  if (data.compare(0, header.size(), header) != 0) {
    throw IoError(path.string() + ": not an OctoMap " + (ext == ".bt" ? ".bt" : ".ot") +
                  " file (no '" + header + "' header)");
  }
  std::istringstream stream(data, std::ios::in | std::ios::binary);
  if (ext == ".bt") {
    auto tree = std::make_unique<octomap::OcTree>(0.1);
    const dem::QuietStderr quiet;
    if (!tree->readBinary(stream)) throw IoError(path.string() + ": not an OctoMap .bt file");
    return tree;
  }
  std::unique_ptr<octomap::AbstractOcTree> tree;
  {
    const dem::QuietStderr quiet;
    tree.reset(octomap::AbstractOcTree::read(stream));
  }
  auto* octree = dynamic_cast<octomap::OcTree*>(tree.get());
  if (octree == nullptr) throw IoError(path.string() + ": not an OctoMap OcTree file");
  tree.release();
  return std::unique_ptr<octomap::OcTree>(octree);
}

}  // namespace rovermap::io
