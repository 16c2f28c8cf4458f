#pragma once
// OctoMap's two file formats written straight into a string: the same bytes as
// OcTree::write (.ot) and OcTree::writeBinaryConst (.bt), several times faster, because those
// call ostream::write once per 1- to 4-byte field of every node (most of a snapshot's and of
// map.bt's time; bench/bench_publish).

#include <octomap/OcTree.h>

#include <string>

namespace rovermap::dem {

/// The .ot bytes: header, then per node in pre-order its log-odds (float) and a byte with a
/// bit per existing child (OcTreeBaseImpl::writeNodesRecurs).
std::string FullOcTreeBytes(const octomap::OcTree& tree);

/// The .bt bytes: header, then per inner node in pre-order two bytes of 2-bit child codes
/// (1 free leaf, 2 occupied leaf, 3 inner, 0 none; OccupancyOcTreeBase::writeBinaryNode).
std::string BinaryOcTreeBytes(const octomap::OcTree& tree);

}  // namespace rovermap::dem
