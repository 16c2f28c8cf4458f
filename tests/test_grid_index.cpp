// Grid indexing: floor semantics on both sides of zero, edges to the positive side, round
// trips, tile/local decomposition, hash distinctness, bad input and geometry validation.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <ostream>
#include <random>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "dem/GridIndex.hpp"

using namespace rovermap::dem;

// Readable values in failure messages and test names.
namespace rovermap::dem {
void PrintTo(const GridGeometry& g, std::ostream* os) {
  *os << "{cell " << g.cell_size_m << " m, tile " << g.tile_cells << "}";
}
void PrintTo(CellIndex c, std::ostream* os) { *os << "cell(" << c.x << ", " << c.y << ")"; }
void PrintTo(TileIndex t, std::ostream* os) { *os << "tile(" << t.x << ", " << t.y << ")"; }
void PrintTo(LocalIndex l, std::ostream* os) { *os << "local(" << l.x << ", " << l.y << ")"; }
}  // namespace rovermap::dem

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

GridIndex MakeIndex(double cell_size_m, int tile_cells) {
  GridGeometry geometry;
  geometry.cell_size_m = cell_size_m;
  geometry.tile_cells = tile_cells;
  return GridIndex(geometry);
}

// Cell sizes that are not binary fractions (0.05, 0.1, 0.3) exercise the rounded edges.
class AnyGeometry : public ::testing::TestWithParam<GridGeometry> {
 protected:
  GridIndex index_{GetParam()};
};

// The definition of a cell: CellOrigin(c) <= v < CellOrigin(c + 1) on each axis.
void ExpectContains(const GridIndex& index, CellIndex c, double x, double y) {
  const Eigen::Vector2d lo = index.CellOrigin(c);
  const Eigen::Vector2d hi = index.CellOrigin({c.x + 1, c.y + 1});
  EXPECT_LE(lo.x(), x) << "cell " << c.x;
  EXPECT_LT(x, hi.x()) << "cell " << c.x;
  EXPECT_LE(lo.y(), y) << "cell " << c.y;
  EXPECT_LT(y, hi.y()) << "cell " << c.y;
}

}  // namespace

INSTANTIATE_TEST_SUITE_P(
    GridIndex, AnyGeometry,
    ::testing::Values(GridGeometry{}, GridGeometry{0.1, 7}, GridGeometry{0.3, 1},
                      GridGeometry{1.0, 256}, GridGeometry{0.125, 64}, GridGeometry{0.07, 100}),
    [](const ::testing::TestParamInfo<GridGeometry>& info) {
      return "cell" + std::to_string(static_cast<int>(std::lround(info.param.cell_size_m * 1000))) +
             "mm_tile" + std::to_string(info.param.tile_cells);
    });

TEST(GridIndex, FloorSemanticsAroundZero) {
  const GridIndex index = MakeIndex(0.05, 256);
  const auto cell = [&](double x) { return index.WorldToCell(x, 0.0)->x; };
  EXPECT_EQ(cell(0.0), 0);
  EXPECT_EQ(cell(-0.0), 0);
  EXPECT_EQ(cell(0.01), 0);
  EXPECT_EQ(cell(0.0499), 0);
  EXPECT_EQ(cell(0.05), 1);    // an edge belongs to the cell on its positive side
  EXPECT_EQ(cell(-0.01), -1);  // floor, not truncation towards zero
  EXPECT_EQ(cell(-1e-300), -1);
  EXPECT_EQ(cell(-0.05), -1);
  EXPECT_EQ(cell(std::nextafter(-0.05, -kInf)), -2);
  EXPECT_EQ(cell(-0.1), -2);
  EXPECT_EQ(cell(-12.8), -256);
  EXPECT_EQ(index.WorldToCell(-0.01, 0.07)->y, 1);
  EXPECT_EQ(index.WorldToCell(0.07, -0.07)->y, -2);
}

TEST_P(AnyGeometry, EdgesBelongToThePositiveSide) {
  std::mt19937_64 rng(1);
  std::uniform_int_distribution<std::int64_t> small(-5000, 5000);
  std::uniform_int_distribution<std::int64_t> large(-(std::int64_t{1} << 48),
                                                    std::int64_t{1} << 48);
  for (int trial = 0; trial < 20000; ++trial) {
    const CellIndex c{trial % 2 ? small(rng) : large(rng), trial % 3 ? small(rng) : large(rng)};
    const Eigen::Vector2d edge = index_.CellOrigin(c);
    const auto at = index_.WorldToCell(edge.x(), edge.y());
    ASSERT_TRUE(at);
    EXPECT_EQ(*at, c) << c.x << " " << c.y;
    // The largest double below the edge is in the previous cell.
    const auto below =
        index_.WorldToCell(std::nextafter(edge.x(), -kInf), std::nextafter(edge.y(), -kInf));
    ASSERT_TRUE(below);
    EXPECT_EQ(*below, (CellIndex{c.x - 1, c.y - 1})) << c.x << " " << c.y;
  }
}

TEST_P(AnyGeometry, CellCenterRoundTrip) {
  std::mt19937_64 rng(2);
  constexpr std::int64_t k48 = std::int64_t{1} << 48;
  std::vector<std::int64_t> values = {0, 1, -1, 2, -2, 255, 256, -256, -257, 1000003, -1000003};
  values.insert(values.end(), {(std::int64_t{1} << 40) + 1, -k48 + 7, k48, -k48});
  std::uniform_int_distribution<std::int64_t> wide(-k48, k48);
  for (int i = 0; i < 2000; ++i) values.push_back(wide(rng) >> (i % 48));
  for (std::int64_t x : values) {
    for (std::int64_t y : {std::int64_t{0}, std::int64_t{-3}, x, -x}) {
      const CellIndex c{x, y};
      const Eigen::Vector2d center = index_.CellCenter(c);
      ExpectContains(index_, c, center.x(), center.y());
      const auto back = index_.WorldToCell(center.x(), center.y());
      ASSERT_TRUE(back);
      EXPECT_EQ(*back, c) << x << " " << y;
    }
  }
}

TEST_P(AnyGeometry, RandomCoordinatesLandInTheirCell) {
  std::mt19937_64 rng(3);
  const double s = GetParam().cell_size_m;
  std::uniform_real_distribution<double> near(-50.0 * s, 50.0 * s);
  std::uniform_real_distribution<double> far(-1e7, 1e7);
  std::uniform_int_distribution<int> k(-100000, 100000);
  for (int trial = 0; trial < 20000; ++trial) {
    double x = trial % 2 ? near(rng) : far(rng);
    // Also products k·s computed differently from CellOrigin, which sit within an ulp of an edge.
    double y = trial % 3 ? near(rng) : (k(rng) * 3) * (s / 3.0);
    const auto c = index_.WorldToCell(x, y);
    ASSERT_TRUE(c);
    ExpectContains(index_, *c, x, y);
    // Agrees with the plain floor wherever that floor is unambiguous.
    const double qx = x / s;
    if (std::abs(qx - std::round(qx)) > 1e-6) {
      EXPECT_EQ(c->x, static_cast<std::int64_t>(std::floor(qx)));
    }
  }
}

TEST_P(AnyGeometry, TileAndLocalDecomposition) {
  const int n = GetParam().tile_cells;
  std::mt19937_64 rng(4);
  std::uniform_int_distribution<std::int64_t> wide(-kMaxCellIndex, kMaxCellIndex);
  std::vector<std::int64_t> values;
  for (std::int64_t v = -3 * n - 2; v <= 3 * n + 2; ++v) values.push_back(v);
  for (int i = 0; i < 2000; ++i) values.push_back(wide(rng));
  values.insert(values.end(),
                {kMaxCellIndex, -kMaxCellIndex, std::numeric_limits<std::int64_t>::max(),
                 std::numeric_limits<std::int64_t>::min()});
  for (std::size_t i = 0; i < values.size(); ++i) {
    const CellIndex c{values[i], values[values.size() - 1 - i]};
    const TileIndex t = index_.CellToTile(c);
    const LocalIndex l = index_.CellToLocal(c);
    ASSERT_GE(l.x, 0);
    ASSERT_LT(l.x, n);
    ASSERT_GE(l.y, 0);
    ASSERT_LT(l.y, n);
    // tile·n + local == cell: modulo 2^64 for every index (TileLocalToCell wraps), and as
    // plain int64 arithmetic within ±kMaxCellIndex.
    EXPECT_EQ(index_.TileLocalToCell(t, l), c);
    const bool in_range = c.x >= -kMaxCellIndex && c.x <= kMaxCellIndex && c.y >= -kMaxCellIndex &&
                          c.y <= kMaxCellIndex;
    if (in_range) {
      EXPECT_EQ(t.x * n + l.x, c.x);
      EXPECT_EQ(t.y * n + l.y, c.y);
      // The tile's corner is its first cell's corner, bit for bit.
      const Eigen::Vector2d origin = index_.TileOrigin(t);
      const Eigen::Vector2d first = index_.CellOrigin(index_.TileLocalToCell(t, {0, 0}));
      EXPECT_EQ(origin.x(), first.x());
      EXPECT_EQ(origin.y(), first.y());
    }
  }
}

TEST(GridIndex, NegativeTilesByHand) {
  const GridIndex index = MakeIndex(0.05, 256);
  EXPECT_EQ(index.CellToTile({-1, 0}), (TileIndex{-1, 0}));
  EXPECT_EQ(index.CellToLocal({-1, 0}), (LocalIndex{255, 0}));
  EXPECT_EQ(index.CellToTile({-256, 255}), (TileIndex{-1, 0}));
  EXPECT_EQ(index.CellToLocal({-256, 255}), (LocalIndex{0, 255}));
  EXPECT_EQ(index.CellToTile({-257, 256}), (TileIndex{-2, 1}));
  EXPECT_EQ(index.CellToLocal({-257, 256}), (LocalIndex{255, 0}));
  const Eigen::Vector2d origin = index.TileOrigin({-1, 2});
  EXPECT_DOUBLE_EQ(origin.x(), -12.8);
  EXPECT_DOUBLE_EQ(origin.y(), 25.6);
  EXPECT_EQ(index.LinearIndex({3, 2}), 2u * 256u + 3u);
  EXPECT_EQ(index.LinearIndex({255, 255}), 256u * 256u - 1u);
  // A world point inside the tile's square maps to a cell of that tile.
  const auto c = index.WorldToCell(-0.01, 25.6);
  ASSERT_TRUE(c);
  EXPECT_EQ(index.CellToTile(*c), (TileIndex{-1, 2}));
  EXPECT_EQ(index.CellToLocal(*c), (LocalIndex{255, 0}));
}

TEST(GridIndex, NonFiniteAndOutOfRangeGiveNullopt) {
  const GridIndex index = MakeIndex(0.05, 256);
  for (double bad : {kNaN, kInf, -kInf, 1e300, -1e300, std::numeric_limits<double>::max()}) {
    EXPECT_FALSE(index.WorldToCell(bad, 0.0)) << bad;
    EXPECT_FALSE(index.WorldToCell(0.0, bad)) << bad;
    EXPECT_FALSE(index.WorldToCell(bad, bad)) << bad;
  }
  // The limit itself is valid on both sides; one cell further is not.
  const Eigen::Vector2d hi = index.CellOrigin({kMaxCellIndex, -kMaxCellIndex});
  const auto at_limit = index.WorldToCell(hi.x(), hi.y());
  ASSERT_TRUE(at_limit);
  EXPECT_EQ(*at_limit, (CellIndex{kMaxCellIndex, -kMaxCellIndex}));
  const Eigen::Vector2d beyond = index.CellOrigin({kMaxCellIndex + 1, 0});
  EXPECT_FALSE(index.WorldToCell(beyond.x(), 0.0));
  EXPECT_FALSE(index.WorldToCell(0.0, std::nextafter(hi.y(), -kInf)));
  // A tiny cell turns an ordinary coordinate into an out-of-range index.
  const GridIndex tiny = MakeIndex(1e-300, 256);
  EXPECT_FALSE(tiny.WorldToCell(1.0, 0.0));
  EXPECT_TRUE(tiny.WorldToCell(1e-290, 0.0));
}

TEST(GridIndex, HashIsDistinctOnNeighbourhoods) {
  const TileIndexHash hash;
  const std::vector<TileIndex> centers = {{0, 0},
                                          {-1, -1},
                                          {-100000, 3000000},
                                          {1 << 30, -(1 << 30)},
                                          {std::int64_t{1} << 40, 5},
                                          {-(std::int64_t{1} << 44), -(std::int64_t{1} << 44)}};
  for (const TileIndex& center : centers) {
    std::unordered_set<std::size_t> seen;
    for (std::int64_t dx = -60; dx <= 60; ++dx) {
      for (std::int64_t dy = -60; dy <= 60; ++dy) {
        EXPECT_TRUE(seen.insert(hash({center.x + dx, center.y + dy})).second)
            << center.x + dx << " " << center.y + dy;
      }
    }
  }
  // Swapped axes and tiles 2^32 apart (same low 32 bits) still differ.
  EXPECT_NE(hash({1, 2}), hash({2, 1}));
  EXPECT_NE(hash({-1, 0}), hash({0, -1}));
  EXPECT_NE(hash({5, 7}), hash({5 + (std::int64_t{1} << 32), 7}));
  EXPECT_NE(hash({5, 7}), hash({5, 7 - (std::int64_t{1} << 32)}));
  EXPECT_EQ(hash({-3, 9}), hash({-3, 9}));

  // Usable as the tile map's hash, and the low bits spread (buckets are hash mod count).
  std::unordered_map<TileIndex, int, TileIndexHash> tiles;
  for (int x = -20; x < 20; ++x) {
    for (int y = -20; y < 20; ++y) tiles[{x, y}] = x * 100 + y;
  }
  EXPECT_EQ(tiles.size(), 1600u);
  EXPECT_EQ(tiles.at({-7, 13}), -687);
  std::unordered_set<std::size_t> low_bits;
  for (const auto& entry : tiles) low_bits.insert(hash(entry.first) & 1023u);
  EXPECT_GT(low_bits.size(), 700u);  // ~815 expected for 1600 uniform draws into 1024
}

TEST(GridIndex, ValidationNamesTheField) {
  const auto message = [](double cell_size_m, int tile_cells) -> std::string {
    try {
      MakeIndex(cell_size_m, tile_cells);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  for (double bad : {0.0, -0.0, -0.05, kNaN, kInf, -kInf}) {
    EXPECT_NE(message(bad, 256).find("cell_size_m"), std::string::npos) << bad;
  }
  for (int bad : {0, -1, -256, std::numeric_limits<int>::min()}) {
    EXPECT_NE(message(0.05, bad).find("tile_cells"), std::string::npos) << bad;
  }
  EXPECT_EQ(message(0.05, 256), "");
  EXPECT_EQ(message(1e-300, 1), "");
  EXPECT_NO_THROW(Validate(GridGeometry{}));
  EXPECT_THROW(Validate(GridGeometry{0.05, 0}), std::invalid_argument);
}

TEST(CellBounds, AccumulatesTouchedCells) {
  CellBounds bounds;
  EXPECT_TRUE(bounds.Empty());
  EXPECT_EQ(bounds.WidthCells(), 0);
  EXPECT_EQ(bounds.HeightCells(), 0);
  EXPECT_FALSE(bounds.Contains({0, 0}));
  EXPECT_THROW(bounds.Min(), std::logic_error);
  EXPECT_THROW(bounds.Max(), std::logic_error);

  bounds.Extend(CellIndex{-3, 5});
  EXPECT_FALSE(bounds.Empty());
  EXPECT_EQ(bounds.Min(), (CellIndex{-3, 5}));
  EXPECT_EQ(bounds.Max(), (CellIndex{-3, 5}));
  EXPECT_EQ(bounds.WidthCells(), 1);
  EXPECT_EQ(bounds.HeightCells(), 1);

  bounds.Extend(CellIndex{4, -2});
  bounds.Extend(CellIndex{0, 0});  // inside: no change
  EXPECT_EQ(bounds.Min(), (CellIndex{-3, -2}));
  EXPECT_EQ(bounds.Max(), (CellIndex{4, 5}));
  EXPECT_EQ(bounds.WidthCells(), 8);
  EXPECT_EQ(bounds.HeightCells(), 8);
  EXPECT_TRUE(bounds.Contains({-3, 5}));
  EXPECT_TRUE(bounds.Contains({4, -2}));
  EXPECT_FALSE(bounds.Contains({5, 0}));
  EXPECT_FALSE(bounds.Contains({0, -3}));

  // Merging: an empty box changes nothing, a disjoint one grows the box; extremes are exact.
  CellBounds other;
  bounds.Extend(other);
  EXPECT_EQ(bounds.Min(), (CellIndex{-3, -2}));
  other.Extend(CellIndex{-kMaxCellIndex, 100});
  other.Extend(CellIndex{kMaxCellIndex, 101});
  bounds.Extend(other);
  EXPECT_EQ(bounds.Min(), (CellIndex{-kMaxCellIndex, -2}));
  EXPECT_EQ(bounds.Max(), (CellIndex{kMaxCellIndex, 101}));
  EXPECT_EQ(bounds.WidthCells(), 2 * kMaxCellIndex + 1);
  EXPECT_EQ(bounds.HeightCells(), 104);
  CellBounds empty;
  empty.Extend(other);
  EXPECT_EQ(empty.Min(), other.Min());
  EXPECT_EQ(empty.Max(), other.Max());
}

TEST(CellBounds, MatchesBruteForceOverWorldPoints) {
  const GridIndex index = MakeIndex(0.05, 256);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-3.0, 2.0);
  CellBounds bounds;
  std::vector<CellIndex> cells;
  for (int i = 0; i < 500; ++i) {
    const auto c = index.WorldToCell(u(rng), u(rng) - 10.0);
    ASSERT_TRUE(c);
    bounds.Extend(*c);
    cells.push_back(*c);
  }
  CellIndex lo = cells.front(), hi = cells.front();
  for (const CellIndex& c : cells) {
    lo = {std::min(lo.x, c.x), std::min(lo.y, c.y)};
    hi = {std::max(hi.x, c.x), std::max(hi.y, c.y)};
    EXPECT_TRUE(bounds.Contains(c));
  }
  EXPECT_EQ(bounds.Min(), lo);
  EXPECT_EQ(bounds.Max(), hi);
}
