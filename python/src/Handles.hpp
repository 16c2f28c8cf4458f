#pragma once
// The C++ objects behind the Python classes that other bindings take as arguments.

#include <pybind11/pybind11.h>

#include <memory>
#include <optional>

#include "dem/ElevationMap.hpp"
#include "io/FrameSource.hpp"
#include "io/Georeference.hpp"

namespace rovermap::python {

/// rovermap.Sequence: an open recording.
struct SequenceHandle {
  std::unique_ptr<io::FrameSource> source;
};

/// rovermap.ElevationMap: a map of its own, or a read-only view of a mapper's (the Python
/// Mapper object keeps it alive), with the georeference its GeoTIFF needs.

class ElevationMapHandle {
 public:
  /// A new map; with a georeference its grid is rotated to the projection's north.
  ElevationMapHandle(const dem::ElevationMapOptions& options,
                     std::optional<io::Georeference> georef);
  /// A view of `view`, which `owner` (the Python Mapper) holds and is kept alive by this.
  ElevationMapHandle(const dem::ElevationMap* view, io::Georeference georef,
                     pybind11::object owner);

  const dem::ElevationMap& Map() const { return *map_; }
  /// @throw py::value_error for a view.
  dem::ElevationMap& Mutable();
  bool ReadOnly() const { return owned_ == nullptr; }
  const std::optional<io::Georeference>& georeference() const { return georef_; }

 private:
  std::shared_ptr<dem::ElevationMap> owned_;
  const dem::ElevationMap* map_ = nullptr;
  std::optional<io::Georeference> georef_;
  pybind11::object owner_;
};

}  // namespace rovermap::python
