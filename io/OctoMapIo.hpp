#pragma once
// map.bt / map.ot: the fused OcTree written atomically (docs/design.md §6).

#include <octomap/OcTree.h>

#include <filesystem>
#include <memory>
#include <string_view>

namespace rovermap::io {

/// What WriteOctoMap wrote.
struct OctoMapFileInfo {
  std::size_t bytes = 0;   ///< file size [bytes]
  std::size_t leaves = 0;  ///< leaf nodes [count], as OcTree::getNumLeafNodes() gives them
};

/// Writes `tree` to `path` atomically: `.bt` as OctoMap's compact binary (maximum-likelihood
/// occupancy), `.ot` as the full tree with probabilities.
/// @throw IoError naming `path` if the extension is neither, serialisation fails, or the file
///        cannot be written.
OctoMapFileInfo WriteOctoMap(const std::filesystem::path& path, const octomap::OcTree& tree);

/// Leaf nodes of a serialised OcTree (`binary`: the .bt format, else .ot), counted in its
/// bytes: the same number as getNumLeafNodes() without a second walk of the tree's pointers.
/// @throw IoError if `data` has no "data" line.
std::size_t CountSerialisedLeaves(std::string_view data, bool binary);

/// Reads a `.bt` or `.ot` file back.
/// @throw IoError naming `path` if it cannot be read or is not an OcTree.
std::unique_ptr<octomap::OcTree> ReadOctoMap(const std::filesystem::path& path);

}  // namespace rovermap::io
