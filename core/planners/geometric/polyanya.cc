// Polyanya on the tiled mesh of convex polygons, and the `navmesh` planner.
//
// Exactness: roots are the start centre or mesh vertices (grid corners), so
// they are lattice points, and an interval is stored not by its end points
// but by the two rays from its root that bound it, each through a lattice
// point (an interval end is either a mesh vertex or where the ray from the
// root through an earlier vertex meets the edge). Every decision (which
// edge a ray leaves a polygon through, whether an end is a vertex, whether
// the goal is in view) is then an integer cross product; floating point
// only enters the heuristic. A turn is taken only at a bend corner (exactly
// one of the four cells blocked) whose blocked cell lies inside the bend: a
// taut path bends nowhere else.
//
// Pruning: the paper's root-level (a node whose root was reached more
// cheaply is dropped, when queued and again when taken), dead-end (no node
// into a polygon with one open edge) and intermediate (a lone successor
// with the same root is expanded at once); and duplicates: on a grid map
// many rays graze vertices exactly, so equal intervals from equal roots are
// reached in several ways, and left alone they multiply at every corner
// (exponentially along a serpentine), so nodes that start a new root or
// sweep a root's fan are queued once per g.
#include "core/planners/geometric/polyanya.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "core/geometry/free_space.h"
#include "core/map/cost_model.h"
#include "core/planners/planners.h"
#include "core/search/derived.h"
#include "core/search/grid_planner.h"

namespace pathd {
namespace {

// A direction in doubled cell coordinates: a difference of two points of a
// grid (sides at most kMaxGridDimension = 2^16 cells), so 32 bits hold it
// and 64 its products.
// Search nodes and their keys are what the search moves through memory,
// so they are kept small.
struct Vec {
  int32_t x = 0;
  int32_t y = 0;
};
Vec Sub(LatticePoint a, LatticePoint b) {
  return Vec{static_cast<int32_t>(a.x2 - b.x2), static_cast<int32_t>(a.y2 - b.y2)};
}
int64_t Cross(Vec a, Vec b) {
  return static_cast<int64_t>(a.x) * b.y - static_cast<int64_t>(a.y) * b.x;
}
// The same direction with coprime components (zero stays zero).
Vec Reduced(Vec v) {
  const int32_t d = std::gcd(v.x < 0 ? -v.x : v.x, v.y < 0 ? -v.y : v.y);
  return d == 0 ? v : Vec{v.x / d, v.y / d};
}

// A search node: the polygon to expand next, the edge it is entered
// through, and the interval of that edge seen from `root`, bounded by the
// rays root + t * left and root + t * right (left and right as seen from
// the root looking into the polygon). When the root lies on the entry
// edge's line (it is then one of the edge's ends), the whole polygon is in
// view and the rays are not used.
struct Node {
  LatticePoint root;
  Vec left;
  Vec right;
  NavRef polygon;
  // Entry edge index in `polygon`; kFinal for a node that reached the goal.
  int32_t edge = 0;
  // The root's entry in PolyanyaScratch::records.
  int32_t record = 0;
  double g = 0.0;
  double f = 0.0;
  // The node's number in PolyanyaScratch::queued, -1 when it was not
  // checked for duplicates.
  int32_t key = -1;
};
constexpr int32_t kFinal = -1;

// A turning point of the path and the one before it.
struct Record {
  LatticePoint point;
  int32_t parent = -1;
};

// A node's identity: the same interval from the same root into the same
// polygon, however it was reached. Duplicates arise wherever the mesh offers
// two equally short ways to one interval (a ray grazing a vertex continues
// on both sides of it; two turns at one corner sweep the same fan), and
// left alone they multiply at every corner after.
struct NodeKey {
  int32_t root_x2, root_y2;
  int32_t lx, ly, rx, ry;
  int32_t tile, polygon;
  int32_t edge;
  friend bool operator==(const NodeKey&, const NodeKey&) = default;
  size_t Hash() const {
    uint64_t h = 0x9e3779b97f4a7c15ull;
    for (const int32_t v : {root_x2, root_y2, lx, ly, rx, ry, tile, polygon, edge}) {
      // splitmix64 over the running value.
      h += static_cast<uint64_t>(v) + 0x9e3779b97f4a7c15ull;
      h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ull;
      h = (h ^ (h >> 27)) * 0x94d049bb133111ebull;
      h ^= h >> 31;
    }
    return static_cast<size_t>(h);
  }
};

// Node identities seen by the search, each numbered (0, 1, ... in order of
// insertion) so that the smallest g it was queued with lives in a plain
// array the node can index when it leaves the open list, without hashing
// its key again. Open addressing over small slots (a fingerprint of the
// key and its number; the keys themselves in insertion order), since a
// probe is usually a cache miss; slots are emptied between searches by a
// stamp, so a search costs nothing for the table's size and its memory is
// kept.
class QueuedTable {
 public:
  // Starts a new search: every slot empty.
  void Clear() {
    keys_.clear();
    if (++stamp_ == 0) {
      for (Slot& s : slots_) s.stamp = 0;
      stamp_ = 1;
    }
  }
  // The number of `key`; `inserted` says whether it is new (then it is the
  // number of keys inserted before it).
  int32_t FindOrInsert(const NodeKey& key, bool& inserted) {
    if (2 * (keys_.size() + 1) > slots_.size()) Grow();
    const size_t hash = key.Hash();
    const uint32_t fingerprint = static_cast<uint32_t>(hash >> 32);
    const size_t mask = slots_.size() - 1;
    for (size_t i = hash & mask;; i = (i + 1) & mask) {
      Slot& s = slots_[i];
      if (s.stamp != stamp_) {
        s = Slot{stamp_, fingerprint, static_cast<int32_t>(keys_.size())};
        keys_.push_back(key);
        inserted = true;
        return s.id;
      }
      if (s.fingerprint == fingerprint && keys_[static_cast<size_t>(s.id)] == key) {
        inserted = false;
        return s.id;
      }
    }
  }
  size_t bytes() const {
    return slots_.capacity() * sizeof(Slot) + keys_.capacity() * sizeof(NodeKey);
  }

 private:
  struct Slot {
    uint32_t stamp = 0;
    uint32_t fingerprint = 0;
    int32_t id = 0;
  };
  void Grow() {
    slots_.assign(std::max<size_t>(1024, 2 * slots_.size()), Slot{});
    stamp_ = 1;
    const size_t mask = slots_.size() - 1;
    for (size_t id = 0; id < keys_.size(); ++id) {
      const size_t hash = keys_[id].Hash();
      size_t i = hash & mask;
      while (slots_[i].stamp == stamp_) i = (i + 1) & mask;
      slots_[i] = Slot{stamp_, static_cast<uint32_t>(hash >> 32), static_cast<int32_t>(id)};
    }
  }

  std::vector<Slot> slots_;
  std::vector<NodeKey> keys_;
  uint32_t stamp_ = 1;
};

// The open list holds the nodes themselves: taking one then reads the
// heap's top, where an index into a node array would cost a cache miss.
// Smallest f first, larger g among equal f (deeper nodes, as the grid
// searches break ties).
bool OpenBefore(const Node& a, const Node& b) {
  return a.f != b.f ? a.f > b.f : a.g < b.g;
}

// Root-level pruning: the best g a vertex (grid corner) was reached with,
// valid where stamp == the search's.
struct CornerG {
  double g = 0.0;
  uint32_t stamp = 0;
};

// What the search keeps in a SearchScratch between queries.
struct PolyanyaScratch final : public SearchScratch::Extension {
  std::vector<Record> records;
  std::vector<Node> open;
  std::vector<Node> pending;
  // The node identities queued, and the smallest g each was queued with.
  QueuedTable queued;
  std::vector<double> queued_g;
  std::vector<CornerG> corner_g;
  uint32_t search = 0;

  size_t MemoryBytes() const override {
    return records.capacity() * sizeof(Record) + open.capacity() * sizeof(Node) +
           pending.capacity() * sizeof(Node) + queued.bytes() +
           queued_g.capacity() * sizeof(double) + corner_g.capacity() * sizeof(CornerG);
  }
};

struct Pt {
  double x;
  double y;
};
Pt ToPt(LatticePoint p) {
  return Pt{static_cast<double>(p.x2), static_cast<double>(p.y2)};
}
double Dist(Pt a, Pt b) {
  const double dx = b.x - a.x;
  const double dy = b.y - a.y;
  return std::sqrt(dx * dx + dy * dy);
}
double CrossD(Pt o, Pt a, Pt b) {
  return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

// Where the ray root + t * dir meets the line through a and b, as a point
// of the segment; exactly a or b when the ray passes through them.
Pt RayHit(LatticePoint root, Vec dir, LatticePoint a, LatticePoint b) {
  if (Cross(dir, Sub(a, root)) == 0) return ToPt(a);
  if (Cross(dir, Sub(b, root)) == 0) return ToPt(b);
  const Vec ab = Sub(b, a);
  const double denom = static_cast<double>(Cross(ab, dir));
  if (denom == 0.0) return ToPt(a);
  // a + s * ab on the ray: Cross(a + s ab - root, dir) = 0.
  const double s = std::clamp(
      static_cast<double>(Cross(Sub(root, a), dir)) / denom, 0.0, 1.0);
  return Pt{static_cast<double>(a.x2) + s * static_cast<double>(ab.x),
            static_cast<double>(a.y2) + s * static_cast<double>(ab.y)};
}

// A lower bound, in doubled units, on a path from `root` through the
// interval l-r to `goal`: the goal is mirrored across the interval's line
// when it lies on the root's side (a path must cross the line and come
// back), then the straight line if it passes the interval, else the bend
// at the nearer end (Polyanya's h).
double IntervalHeuristic(Pt root, Pt l, Pt r, Pt goal) {
  if ((root.x == l.x && root.y == l.y) || (root.x == r.x && root.y == r.y)) {
    return Dist(root, goal);
  }
  if (l.x == r.x && l.y == r.y) return Dist(root, l) + Dist(l, goal);
  const double side_root = CrossD(l, r, root);
  const double side_goal = CrossD(l, r, goal);
  if ((side_root > 0) == (side_goal > 0)) {
    const double dx = r.x - l.x;
    const double dy = r.y - l.y;
    const double t = ((goal.x - l.x) * dx + (goal.y - l.y) * dy) / (dx * dx + dy * dy);
    goal = Pt{2 * (l.x + t * dx) - goal.x, 2 * (l.y + t * dy) - goal.y};
  }
  const double ol = CrossD(root, goal, l);
  const double orr = CrossD(root, goal, r);
  if ((ol <= 0 && orr >= 0) || (ol >= 0 && orr <= 0)) return Dist(root, goal);
  return std::min(Dist(root, l) + Dist(l, goal), Dist(root, r) + Dist(r, goal));
}

class Search {
 public:
  Search(const NavMesh& mesh, const Grid& grid, Cell start, Cell goal,
         const StopCondition& stop, PolyanyaScratch& s)
      : mesh_(mesh),
        grid_(grid),
        start_(CentreOf(start)),
        goal_(CentreOf(goal)),
        goal_polygons_(mesh.Locate(goal)),
        stop_(stop),
        s_(s) {}

  PolyanyaPath Run(Cell start_cell) {
    PolyanyaPath out;
    const std::vector<NavRef> start_polygons = mesh_.Locate(start_cell);
    if (start_polygons.empty() || goal_polygons_.empty()) return out;
    for (const NavRef& p : start_polygons) {
      if (IsGoalPolygon(p)) {
        // Both points in one convex polygon: the straight segment.
        out.outcome = PlanOutcome::kFound;
        out.polyline = {start_};
        if (!(goal_ == start_)) out.polyline.push_back(goal_);
        return out;
      }
    }
    Reset();
    s_.records.push_back(Record{start_, -1});
    for (const NavRef& p : start_polygons) {
      const NavPolygonView poly = mesh_.polygon(p);
      for (int32_t i = 0; i < poly.size; ++i) {
        const LatticePoint u = poly.corner(i);
        const LatticePoint w = poly.corner(i + 1);
        // An edge through the start belongs to the other start polygon.
        if (Orient(u, w, start_) == 0) continue;
        Push(start_, Sub(w, start_), Sub(u, start_), p, i, 0.0, 0);
      }
    }
    FlushPending();
    while (!s_.open.empty()) {
      const PlanOutcome o = stop_.Check(out.expansions, s_.open.front().f);
      if (o != PlanOutcome::kFound) {
        out.outcome = o;
        return out;
      }
      std::pop_heap(s_.open.begin(), s_.open.end(), OpenBefore);
      Node node = s_.open.back();
      // A lower bound on the f of the lone successors expanded below.
      const double f = node.f;
      s_.open.pop_back();
      if (Superseded(node)) continue;
      ++out.expansions;
      if (node.edge == kFinal) {
        out.outcome = PlanOutcome::kFound;
        out.polyline = Trace(node.record);
        return out;
      }
      Expand(node);
      // Intermediate pruning (the paper's): a lone successor with the same
      // root is expanded at once instead of through the open list.
      while (s_.pending.size() == 1 && s_.pending[0].edge != kFinal &&
             s_.pending[0].record == node.record) {
        const PlanOutcome o2 = stop_.Check(out.expansions, f);
        if (o2 != PlanOutcome::kFound) {
          out.outcome = o2;
          return out;
        }
        node = s_.pending[0];
        s_.pending.clear();
        ++out.expansions;
        Expand(node);
      }
      FlushPending();
    }
    out.outcome = PlanOutcome::kNoPath;
    return out;
  }

 private:
  void Reset() {
    const size_t corners = static_cast<size_t>(grid_.width() + 1) * (grid_.height() + 1);
    if (s_.corner_g.size() != corners) {
      s_.corner_g.assign(corners, CornerG{});
      s_.search = 0;
    }
    if (++s_.search == 0) {
      std::fill(s_.corner_g.begin(), s_.corner_g.end(), CornerG{});
      s_.search = 1;
    }
    s_.records.clear();
    s_.open.clear();
    s_.pending.clear();
    s_.queued.Clear();
    s_.queued_g.clear();
  }

  bool IsGoalPolygon(NavRef p) const {
    return std::find(goal_polygons_.begin(), goal_polygons_.end(), p) !=
           goal_polygons_.end();
  }

  bool Blocked(int64_t x, int64_t y) const {
    return x < 0 || y < 0 || x >= grid_.width() || y >= grid_.height() ||
           !Traversable(grid_.cost(static_cast<int32_t>(x), static_cast<int32_t>(y)),
                        mesh_.unknown_is_free());
  }
  // Whether a path from `from` may bend at vertex v, turning left (or
  // right): v must be a bend corner (exactly one of its four cells
  // blocked) with that cell reaching into the open half-plane the path
  // turns towards. A taut path bends round an obstacle inside the bend;
  // elsewhere the mesh merely ends an interval at v, and a turn there could
  // be cut short.
  bool CanTurn(LatticePoint from, LatticePoint v, bool left) const {
    const int64_t x = v.x2 / 2;
    const int64_t y = v.y2 / 2;
    int blocked = 0;
    Vec quadrant;
    for (const int dy : {-1, 1}) {
      for (const int dx : {-1, 1}) {
        if (Blocked(dx < 0 ? x - 1 : x, dy < 0 ? y - 1 : y)) {
          ++blocked;
          quadrant = Vec{dx, dy};
        }
      }
    }
    if (blocked != 1) return false;
    const Vec d = Sub(v, from);
    const int64_t sign = left ? 1 : -1;
    // The blocked cell's corners other than v, relative to v.
    return sign * Cross(d, Vec{2 * quadrant.x, 0}) > 0 ||
           sign * Cross(d, Vec{0, 2 * quadrant.y}) > 0 ||
           sign * Cross(d, Vec{2 * quadrant.x, 2 * quadrant.y}) > 0;
  }

  size_t CornerId(LatticePoint corner) const {
    return static_cast<size_t>(corner.y2 / 2) * (grid_.width() + 1) +
           static_cast<size_t>(corner.x2 / 2);
  }

  // Root-level pruning (the paper's): a node whose root, a vertex, was
  // already reached more cheaply is dominated. False when pruned.
  bool RecordRootG(LatticePoint root, double g) {
    if (root == start_) return true;
    const size_t id = CornerId(root);
    CornerG& c = s_.corner_g[id];
    if (c.stamp != s_.search) {
      c = CornerG{g, s_.search};
      return true;
    }
    if (g > c.g + 1e-9) return false;
    c.g = std::min(c.g, g);
    return true;
  }

  int32_t Turn(LatticePoint at, int32_t parent) {
    s_.records.push_back(Record{at, parent});
    return static_cast<int32_t>(s_.records.size() - 1);
  }

  // Successors wait in `pending` until their parent's expansion is done.
  void PushEntry(const Node& n) { s_.pending.push_back(n); }
  void FlushPending() {
    for (Node& n : s_.pending) {
      SetF(n);
      s_.open.push_back(n);
      std::push_heap(s_.open.begin(), s_.open.end(), OpenBefore);
    }
    s_.pending.clear();
  }

  // Queues the interval of edge `edge` of `from` bounded by the rays
  // `left`, `right` from `root`, as a node of the polygon across it.
  void Push(LatticePoint root, Vec left, Vec right, NavRef from, int edge,
            double g, int32_t record) {
    const NavRef next = mesh_.Across(from, edge);
    if (!next.valid() || (DeadEnd(next) && !IsGoalPolygon(next))) return;
    const NavPolygonView fp = mesh_.polygon(from);
    // The next polygon's entry edge runs a -> b.
    const LatticePoint a = fp.corner(edge + 1);
    const LatticePoint b = fp.corner(edge);
    const bool on_line = Orient(a, b, root) == 0;
    // On the edge's line only an end of the edge may be the root.
    if (on_line && !(root == a) && !(root == b)) return;
    if (!RecordRootG(root, g)) return;
    const NavPolygonView np = mesh_.polygon(next);
    int32_t entry = 0;
    while (!(np.corner(entry) == a)) ++entry;
    Node node{root, left, right, next, entry, record, g, 0.0};
    // Only a turn (a root new to this branch) or a sweep round a root's fan
    // can meet a node queued before; the cone of one root splits without
    // overlap.
    if (record != expanding_record_ || on_line) {
      bool inserted = false;
      node.key = s_.queued.FindOrInsert(KeyOf(node), inserted);
      if (inserted) {
        s_.queued_g.push_back(g);
      } else {
        double& queued = s_.queued_g[static_cast<size_t>(node.key)];
        if (queued <= g + 1e-9) return;
        queued = g;
      }
    }
    PushEntry(node);
  }

  // f = g + h of a node entering the open list. Left until then because a
  // lone successor with its parent's root is expanded at once (intermediate
  // pruning) and never needs it.
  void SetF(Node& n) const {
    if (n.edge == kFinal) return;
    const NavPolygonView p = mesh_.polygon(n.polygon);
    const LatticePoint a = p.corner(n.edge);
    const LatticePoint b = p.corner(n.edge + 1);
    const bool on_line = Orient(a, b, n.root) == 0;
    const Pt l = on_line ? ToPt(a) : RayHit(n.root, n.left, a, b);
    const Pt r = on_line ? ToPt(b) : RayHit(n.root, n.right, a, b);
    n.f = n.g + 0.5 * IntervalHeuristic(ToPt(n.root), l, r, ToPt(goal_));
  }

  // A polygon with one open edge: whatever enters it can only leave the
  // way it came (dead-end pruning, from the paper).
  bool DeadEnd(NavRef p) const {
    return mesh_.polygon(p).open <= 1;
  }

  NodeKey KeyOf(const Node& n) const {
    // Rays only matter off the entry edge's line.
    const NavPolygonView p = mesh_.polygon(n.polygon);
    const bool on_line = Orient(p.corner(n.edge), p.corner(n.edge + 1), n.root) == 0;
    const Vec l = on_line ? Vec{} : Reduced(n.left);
    const Vec r = on_line ? Vec{} : Reduced(n.right);
    return NodeKey{static_cast<int32_t>(n.root.x2), static_cast<int32_t>(n.root.y2),
                   l.x, l.y, r.x, r.y,
                   n.polygon.tile, n.polygon.polygon, n.edge};
  }
  // A node queued again later with a smaller g, or whose root has been
  // reached more cheaply since it was queued (root-level pruning applied
  // again when it leaves the open list).
  bool Superseded(const Node& n) const {
    if (n.edge == kFinal) return false;
    if (!(n.root == start_)) {
      const size_t id = CornerId(n.root);
      const CornerG& c = s_.corner_g[id];
      if (c.stamp == s_.search && c.g < n.g - 1e-9) return true;
    }
    return n.key >= 0 && s_.queued_g[static_cast<size_t>(n.key)] < n.g - 1e-9;
  }

  void PushFinal(double g, int32_t record) {
    Node n;
    n.edge = kFinal;
    n.g = g;
    n.f = g;
    n.record = record;
    PushEntry(n);
  }

  // The polygon's boundary beyond the entry edge a -> b, as seen from the
  // root: the far chain w_0 = b, w_1, ..., w_m = a (counter-clockwise, so
  // from the right of the cone to its left), edge j running w_j -> w_j+1.
  struct FarChain {
    NavPolygonView polygon;
    int32_t entry;
    int32_t m() const { return polygon.size - 1; }
    LatticePoint w(int32_t j) const { return polygon.corner(entry + 1 + j); }
    int32_t edge(int32_t j) const {
      const int32_t i = entry + 1 + j;
      return i < polygon.size ? i : i - polygon.size;
    }
  };

  void Expand(const Node& node) {
    expanding_record_ = node.record;
    const FarChain chain{mesh_.polygon(node.polygon), node.edge};
    const int32_t m = chain.m();
    const LatticePoint a = chain.w(m);
    const LatticePoint b = chain.w(0);
    const LatticePoint s = node.root;
    if (Orient(a, b, s) == 0) {
      ExpandFromVertex(node, chain);
      return;
    }
    // The far corners strictly right of the right ray are w_1 .. w_r, those
    // strictly left of the left ray w_l .. w_m-1 (the chain is in angular
    // order as seen from the root, as far as the cone reaches); the cone
    // leaves through edges r .. l - 1, cut at the far corners between.
    int32_t r = 0;
    while (r + 1 < m && Cross(node.right, Sub(chain.w(r + 1), s)) < 0) ++r;
    int32_t l = m;
    while (l - 1 > r && Cross(node.left, Sub(chain.w(l - 1), s)) > 0) --l;
    const bool left_at_a = Cross(node.left, Sub(a, s)) == 0;
    const bool right_at_b = Cross(node.right, Sub(b, s)) == 0;

    if (IsGoalPolygon(node.polygon)) {
      const Vec sg = Sub(goal_, s);
      const int64_t gl = Cross(node.left, sg);
      const int64_t gr = Cross(node.right, sg);
      if (gl <= 0 && gr >= 0) {
        PushFinal(node.g + Distance(s, goal_), node.record);
      } else if (gl > 0 && left_at_a && CanTurn(s, a, /*left=*/true)) {
        PushFinal(node.g + Distance(s, a) + Distance(a, goal_), Turn(a, node.record));
      } else if (gr < 0 && right_at_b && CanTurn(s, b, /*left=*/false)) {
        PushFinal(node.g + Distance(s, b) + Distance(b, goal_), Turn(b, node.record));
      }
    }

    // Observable successors: the cone beyond the entry interval, one node
    // per edge it leaves through. A ray through a far corner exactly gives
    // a one-point interval on the edge beyond it: past the corner the
    // point walks round the corner's fan, so a path going straight on past
    // it finds the side an obstacle there leaves open.
    for (int32_t j = r; j < l; ++j) {
      const Vec right = j == r ? node.right : Sub(chain.w(j), s);
      const Vec left = j + 1 == l ? node.left : Sub(chain.w(j + 1), s);
      Push(s, left, right, node.polygon, chain.edge(j), node.g, node.record);
    }

    // Non-observable successors: around an end of the interval that is an
    // obstacle corner, with that corner as the new root: the edges beyond
    // the cone on that side, the one the cone's ray crosses from the ray's
    // continuation past the corner.
    if (left_at_a && CanTurn(s, a, /*left=*/true)) {
      const double g = node.g + Distance(s, a);
      if (RecordRootG(a, g)) {
        const int32_t rec = Turn(a, node.record);
        if (l < m) {
          Push(a, Sub(chain.w(l), a), Sub(a, s), node.polygon, chain.edge(l - 1), g, rec);
        }
        for (int32_t j = l; j + 1 < m; ++j) {
          Push(a, Sub(chain.w(j + 1), a), Sub(chain.w(j), a), node.polygon, chain.edge(j),
               g, rec);
        }
        Push(a, Vec{}, Sub(chain.w(m - 1), a), node.polygon, chain.edge(m - 1), g, rec);
      }
    }
    if (right_at_b && CanTurn(s, b, /*left=*/false)) {
      const double g = node.g + Distance(s, b);
      if (RecordRootG(b, g)) {
        const int32_t rec = Turn(b, node.record);
        if (r > 0) {
          Push(b, Sub(b, s), Sub(chain.w(r), b), node.polygon, chain.edge(r), g, rec);
        }
        for (int32_t j = 1; j < r; ++j) {
          Push(b, Sub(chain.w(j + 1), b), Sub(chain.w(j), b), node.polygon, chain.edge(j),
               g, rec);
        }
        Push(b, Sub(chain.w(1), b), Vec{}, node.polygon, chain.edge(0), g, rec);
      }
    }
  }

  // The root is an end of the entry edge (a vertex of the polygon), so the
  // whole polygon is in view: every other edge, whole.
  void ExpandFromVertex(const Node& node, const FarChain& chain) {
    const LatticePoint s = node.root;
    if (!(s == chain.w(chain.m())) && !(s == chain.w(0))) return;
    if (IsGoalPolygon(node.polygon)) {
      PushFinal(node.g + Distance(s, goal_), node.record);
    }
    for (int32_t j = 0; j < chain.m(); ++j) {
      Push(s, Sub(chain.w(j + 1), s), Sub(chain.w(j), s), node.polygon, chain.edge(j),
           node.g, node.record);
    }
  }

  // The turning points from the start to the goal. A turn can be recorded
  // at a corner the path only grazes (it continues straight on, at the
  // same g as the path that never turned), so points on the straight
  // segment between their neighbours are dropped.
  std::vector<LatticePoint> Trace(int32_t record) const {
    std::vector<LatticePoint> reversed{goal_};
    for (int32_t r = record; r >= 0; r = s_.records[static_cast<size_t>(r)].parent) {
      reversed.push_back(s_.records[static_cast<size_t>(r)].point);
    }
    std::vector<LatticePoint> polyline;
    for (auto it = reversed.rbegin(); it != reversed.rend(); ++it) {
      const LatticePoint p = *it;
      if (polyline.size() >= 2) {
        const LatticePoint a = polyline[polyline.size() - 2];
        const LatticePoint m = polyline.back();
        const Vec am = Sub(m, a);
        const Vec mp = Sub(p, m);
        if (Cross(am, mp) == 0 && am.x * mp.x + am.y * mp.y > 0) polyline.pop_back();
      }
      polyline.push_back(p);
    }
    return polyline;
  }

  const NavMesh& mesh_;
  const Grid& grid_;
  const LatticePoint start_;
  const LatticePoint goal_;
  const std::vector<NavRef> goal_polygons_;
  const StopCondition& stop_;
  PolyanyaScratch& s_;
  // The root record of the node being expanded (the start's while seeding).
  int32_t expanding_record_ = 0;
};

class NavMeshPlanner final : public GridPlanner {
 public:
  NavMeshPlanner()
      : GridPlanner("navmesh",
                    PlannerTraits{
                        .optimal = true,
                        .needs_uniform_cost = true,
                        .needs_eight_connected = true,
                        .geometric = true,
                        .description =
                            "Polyanya on a tiled navigation mesh of convex "
                            "polygons: Euclidean shortest paths bending at obstacle "
                            "corners; uniform-cost 8-connected maps only; "
                            "expansions count search nodes (edge intervals)"}) {}

 protected:
  // Uniform cost needs every cell read: the mesh keeps the cost values of
  // each tile, so Search() checks it in O(tiles) and runs the full
  // ValidateRequest only to word the error when it fails (as jps does).
  absl::Status Validate(const Grid& grid,
                        const PlanRequest& request) const override {
    PlannerTraits endpoint_traits = traits();
    endpoint_traits.needs_uniform_cost = false;
    return ValidateRequest(grid, request, name(), endpoint_traits);
  }

  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    const Grid& grid = q.grid;
    const PlanRequest& request = q.request;
    const bool unknown_is_free = request.cost.unknown_is_free;
    const std::shared_ptr<const NavMesh> mesh = GetDerived<NavMesh>(
        request.derived, grid,
        std::string("navmesh unknown_is_free=") + (unknown_is_free ? "1" : "0"),
        [unknown_is_free](const Grid& g) { return NavMesh::Build(g, unknown_is_free); },
        [](const NavMesh& previous, const Grid& g, absl::Span<const Cell> changed) {
          return NavMesh::Advance(previous, g, changed);
        },
        [](const NavMesh& m) { return m.bytes(); });
    if (request.cost.cost_weight != 0.0 && !mesh->UniformCost()) {
      return ValidateRequest(grid, request, name(), traits());
    }
    PolyanyaPath path = PolyanyaSearch(*mesh, grid, request.start, request.goal,
                                       q.stop, q.scratch);
    PlanResult result;
    result.outcome = path.outcome;
    result.expansions = path.expansions;
    if (!result.found()) return result;
    // The free-space bitmap is derived per version too: building it here
    // would cost a pass over the map on every query.
    const std::shared_ptr<const FreeSpace> space =
        SharedFreeSpace(request.derived, grid, unknown_is_free);
    // Every traversable cell costs what the start cell costs.
    FillPolylineResult(*space, path.polyline,
                       CellFactor(grid.cost(request.start), request.cost.cost_weight),
                       result);
    return result;
  }
};

}  // namespace

PolyanyaPath PolyanyaSearch(const NavMesh& mesh, const Grid& grid, Cell start,
                            Cell goal, const StopCondition& stop,
                            SearchScratch& scratch) {
  PolyanyaScratch& s = scratch.extension<PolyanyaScratch>();
  return Search(mesh, grid, start, goal, stop, s).Run(start);
}

std::unique_ptr<Planner> MakeNavMeshPlanner() {
  return std::make_unique<NavMeshPlanner>();
}

}  // namespace pathd
