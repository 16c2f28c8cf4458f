#pragma once
// The heap as the commands that run many frames keep it.

#include <malloc.h>

namespace rovermap::core {

/// Every frame allocates and frees tens of MB (a KITTI frame's disparity, points, covariances).
/// glibc maps blocks that large afresh and returns freed memory to the system, so each frame
/// paid page faults for all of it again (docs/benchmarks.md, "Replay on real stereo"). Kept in
/// the heap, the pages are reused: the peak stays that of the largest frames in flight.
inline void KeepFreedMemoryInHeap() {
  ::mallopt(M_MMAP_THRESHOLD, 32 << 20);  // glibc's largest; blocks below it come from the heap
  ::mallopt(M_TRIM_THRESHOLD, 1 << 30);   // never give the heap's free top back mid-run
  ::mallopt(M_TOP_PAD, 64 << 20);         // grow a heap in large steps
}

}  // namespace rovermap::core
