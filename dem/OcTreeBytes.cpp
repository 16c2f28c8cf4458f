#include "dem/OcTreeBytes.hpp"

#include <cstdint>
#include <sstream>

namespace rovermap::dem {
namespace {

// AbstractOcTree::write's and AbstractOccupancyOcTree::writeBinaryConst's header, through a
// stream as theirs is, so that the resolution prints exactly alike.
std::string Header(const octomap::OcTree& tree, const char* first_line) {
  std::ostringstream s;
  s << first_line
    << "\n# (feel free to add / change comments, but leave the first line as it is!)\n#\n";
  s << "id " << tree.getTreeType() << std::endl;
  s << "size " << tree.size() << std::endl;
  s << "res " << tree.getResolution() << std::endl;
  s << "data" << std::endl;
  return s.str();
}

void AppendFull(const octomap::OcTree& tree, const octomap::OcTreeNode* node, std::string* out) {
  const float value = node->getValue();
  out->append(reinterpret_cast<const char*>(&value), sizeof(value));
  unsigned children = 0;
  for (unsigned i = 0; i < 8; ++i) children |= tree.nodeChildExists(node, i) ? 1U << i : 0U;
  out->push_back(static_cast<char>(children));
  for (unsigned i = 0; i < 8; ++i)
    if ((children >> i) & 1U) AppendFull(tree, tree.getNodeChild(node, i), out);
}

void AppendBinary(const octomap::OcTree& tree, const octomap::OcTreeNode* node, std::string* out) {
  std::uint16_t codes = 0;  // child i in bits 2i, 2i+1 (bytes: children 0-3, then 4-7)
  for (unsigned i = 0; i < 8; ++i) {
    if (!tree.nodeChildExists(node, i)) continue;
    const octomap::OcTreeNode* child = tree.getNodeChild(node, i);
    const unsigned code = tree.nodeHasChildren(child) ? 3U : tree.isNodeOccupied(child) ? 2U : 1U;
    codes |= static_cast<std::uint16_t>(code << (2 * i));
  }
  out->push_back(static_cast<char>(codes & 0xFFU));
  out->push_back(static_cast<char>(codes >> 8));
  for (unsigned i = 0; i < 8; ++i) {
    if (((codes >> (2 * i)) & 3U) == 3U) AppendBinary(tree, tree.getNodeChild(node, i), out);
  }
}

template <typename Append>
std::string Bytes(const octomap::OcTree& tree, const char* first_line, std::size_t per_node,
                  Append append) {
  std::string bytes = Header(tree, first_line);
  bytes.reserve(bytes.size() + per_node * tree.size());  // every node once at most
  if (tree.getRoot() != nullptr) append(tree, tree.getRoot(), &bytes);
  return bytes;
}

}  // namespace

std::string FullOcTreeBytes(const octomap::OcTree& tree) {
  return Bytes(tree, "# Octomap OcTree file", sizeof(float) + 1, AppendFull);
}

std::string BinaryOcTreeBytes(const octomap::OcTree& tree) {
  return Bytes(tree, "# Octomap OcTree binary file", 2, AppendBinary);
}

}  // namespace rovermap::dem
