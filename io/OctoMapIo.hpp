#pragma once
// map.bt / map.ot: the fused OcTree written atomically (DESIGN §6).

#include <octomap/OcTree.h>

#include <filesystem>
#include <memory>

namespace rovermap::io {

/// Writes `tree` to `path` atomically: `.bt` as OctoMap's compact binary (maximum-likelihood
/// occupancy), `.ot` as the full tree with probabilities.
/// @throw IoError naming `path` if the extension is neither, serialisation fails, or the file
///        cannot be written.
void WriteOctoMap(const std::filesystem::path& path, const octomap::OcTree& tree);

/// Reads a `.bt` or `.ot` file back.
/// @throw IoError naming `path` if it cannot be read or is not an OcTree.
std::unique_ptr<octomap::OcTree> ReadOctoMap(const std::filesystem::path& path);

}  // namespace rovermap::io
