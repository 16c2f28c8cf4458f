#include "io/OctoMapIo.hpp"

#include <octomap/AbstractOcTree.h>

#include <sstream>

#include "dem/QuietStderr.hpp"
#include "io/FileUtil.hpp"
#include "io/IoError.hpp"

namespace rovermap::io {

void WriteOctoMap(const std::filesystem::path& path, const octomap::OcTree& tree) {
  std::ostringstream stream(std::ios::out | std::ios::binary);
  const std::string ext = path.extension().string();
  bool ok = false;
  if (ext == ".bt") {
    const dem::QuietStderr quiet;  // liboctomap prints " done." after a binary write
    ok = tree.writeBinaryConst(stream);
  } else if (ext == ".ot") {
    ok = tree.write(stream);
  } else {
    throw IoError(path.string() + ": OctoMap files must end in .bt or .ot");
  }
  if (!ok || !stream) throw IoError(path.string() + ": cannot serialise the OcTree");
  WriteFileAtomically(path, stream.str());
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
