#include "core/overlap_check.hpp"

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <limits>
#include <numbers>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/boundary.hpp"
#include "core/error.hpp"

namespace depthfem {

namespace {

// Distances below kRelativeTolerance x (the longest edge of a triangle pair) count as zero, and
// so do those below kRoundingFloor x (the largest coordinate magnitude), the rounding of a
// difference of coordinates far from the origin.
constexpr double kRelativeTolerance = 1e-10;
constexpr double kRoundingFloor = 1e-13;

struct Box {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = Vec3::Constant(-std::numeric_limits<double>::infinity());

  void add(const Vec3& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void add(const Box& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  bool meets(const Box& b) const {
    return (lo.array() <= b.hi.array()).all() && (b.lo.array() <= hi.array()).all();
  }
  bool holds(const Vec3& p) const {
    return (lo.array() <= p.array()).all() && (p.array() <= hi.array()).all();
  }
};

// A bounding-volume tree over boxes: median splits along the longest axis of the box centres,
// leaves of at most four boxes. Balanced, so its depth is about log2(#boxes).
class BoxTree {
 public:
  explicit BoxTree(const std::vector<Box>& boxes) : boxes_(boxes) {
    order_.resize(boxes.size());
    centres_.resize(boxes.size());
    for (size_t i = 0; i < boxes.size(); ++i) {
      order_[i] = static_cast<Index>(i);
      centres_[i] = 0.5 * (boxes[i].lo + boxes[i].hi);
    }
    if (boxes.empty()) return;
    nodes_.reserve(boxes.size());
    nodes_.resize(1);
    build(0, 0, static_cast<Index>(boxes.size()));
    // The boxes in tree order, so that a leaf's boxes lie together in memory.
    sorted_.reserve(boxes.size());
    for (const Index i : order_) sorted_.push_back(boxes[i]);
  }

  // Calls visit(i, j), i < j, for every pair of boxes that meet, until visit returns false.
  template <class Visit>
  void for_each_meeting_pair(Visit&& visit) const {
    if (!nodes_.empty()) pairs(0, 0, visit);
  }

  // Calls visit(i) for every box that holds p.
  template <class Visit>
  void for_each_holding(const Vec3& p, Visit&& visit) const {
    if (nodes_.empty()) return;
    std::vector<Index> stack = {0};
    while (!stack.empty()) {
      const Node& n = nodes_[stack.back()];
      stack.pop_back();
      if (!n.box.holds(p)) continue;
      if (n.left < 0) {
        for (Index k = n.first; k < n.first + n.count; ++k)
          if (sorted_[k].holds(p)) visit(order_[k]);
      } else {
        stack.push_back(n.left);
        stack.push_back(n.left + 1);
      }
    }
  }

 private:
  struct Node {
    Box box;
    Index first = 0, count = 0;
    Index left = -1;  // children left and left + 1; -1 for a leaf
  };

  // Fills node `slot` with the boxes order_[first, first + count) and builds its children.
  void build(Index slot, Index first, Index count) {
    Box box, centres;
    for (Index k = first; k < first + count; ++k) {
      box.add(boxes_[order_[k]]);
      centres.add(centres_[order_[k]]);
    }
    nodes_[slot] = {box, first, count, -1};
    if (count <= 4) return;
    int axis = 0;
    (centres.hi - centres.lo).maxCoeff(&axis);
    const Index half = count / 2;
    std::nth_element(order_.begin() + first, order_.begin() + first + half,
                     order_.begin() + first + count, [&](Index a, Index b) {
                       const double ca = centres_[a][axis], cb = centres_[b][axis];
                       return ca != cb ? ca < cb : a < b;
                     });
    const Index left = static_cast<Index>(nodes_.size());
    nodes_.resize(nodes_.size() + 2);
    nodes_[slot].left = left;
    build(left, first, half);
    build(left + 1, first + half, count - half);
  }

  template <class Visit>
  bool pairs(Index a, Index b, Visit& visit) const {
    const Node &na = nodes_[a], &nb = nodes_[b];
    if (a != b && !na.box.meets(nb.box)) return true;
    if (na.left < 0 && nb.left < 0) {
      for (Index i = na.first; i < na.first + na.count; ++i) {
        for (Index j = a == b ? i + 1 : nb.first; j < nb.first + nb.count; ++j) {
          const Index x = order_[i], y = order_[j];
          if (sorted_[i].meets(sorted_[j]) && !visit(std::min(x, y), std::max(x, y))) return false;
        }
      }
      return true;
    }
    if (a == b) {
      return pairs(na.left, na.left, visit) && pairs(na.left + 1, na.left + 1, visit) &&
             pairs(na.left, na.left + 1, visit);
    }
    if (nb.left < 0 || (na.left >= 0 && na.count >= nb.count)) {
      return pairs(na.left, b, visit) && pairs(na.left + 1, b, visit);
    }
    return pairs(a, nb.left, visit) && pairs(a, nb.left + 1, visit);
  }

  const std::vector<Box>& boxes_;
  std::vector<Vec3> centres_;
  std::vector<Index> order_;
  std::vector<Box> sorted_;
  std::vector<Node> nodes_;
};

// A boundary triangle of the body, counter-clockwise seen from outside.
struct Triangle {
  std::array<Index, 3> node;
  std::array<Vec3, 3> p;
  Vec3 normal;  // unit, outward
  double tol;   // distances below this count as zero
  double longest;
  Index tet;  // the tet it bounds

  Vec3 centroid() const { return (p[0] + p[1] + p[2]) / 3.0; }
  double distance(const Vec3& x) const { return normal.dot(x - p[0]); }
};

int sign(double d, double tol) {
  return d > tol ? 1 : d < -tol ? -1 : 0;
}

// Whether the segment [x, y], taken in the plane of t, passes through the interior of t deeper
// than tol inside each of its edges over more than a point; x == y asks it of a point.
bool enters_interior(const Triangle& t, const Vec3& x, const Vec3& y, double tol) {
  double lo = 0.0, hi = 1.0;
  for (int k = 0; k < 3; ++k) {
    const Vec3& a = t.p[k];
    const Vec3 inward = t.normal.cross(t.p[(k + 1) % 3] - a).normalized();
    const double ex = inward.dot(x - a) - tol, ey = inward.dot(y - a) - tol;  // > 0: inside
    if (ex <= 0 && ey <= 0) return false;
    if (ex < 0 || ey < 0) {
      const double s = ex / (ex - ey);
      if (ex < 0) {
        lo = std::max(lo, s);
      } else {
        hi = std::min(hi, s);
      }
    }
  }
  return lo < hi;
}

// Area of the part of f deeper than tol inside each edge of t, f taken in t's plane
// (Sutherland-Hodgman clipping: a triangle clipped by three lines has at most six corners).
double overlap_area(const Triangle& f, const Triangle& t, double tol) {
  std::array<Vec3, 6> poly, next;
  std::copy(f.p.begin(), f.p.end(), poly.begin());
  int size = 3;
  for (int k = 0; k < 3 && size > 0; ++k) {
    const Vec3& a = t.p[k];
    const Vec3 inward = t.normal.cross(t.p[(k + 1) % 3] - a).normalized();
    const auto depth = [&](const Vec3& x) { return inward.dot(x - a) - tol; };
    int kept = 0;
    for (int i = 0; i < size; ++i) {
      const Vec3 &x = poly[i], &y = poly[(i + 1) % size];
      const double dx = depth(x), dy = depth(y);
      if (dx >= 0) next[kept++] = x;
      if ((dx >= 0) != (dy >= 0)) next[kept++] = x + (y - x) * (dx / (dx - dy));
    }
    std::swap(poly, next);
    size = kept;
  }
  Vec3 twice_area = Vec3::Zero();
  for (int i = 1; i + 1 < size; ++i) twice_area += (poly[i] - poly[0]).cross(poly[i + 1] - poly[0]);
  return 0.5 * twice_area.norm();
}

enum class Contact { kNone, kCross, kCoplanar, kTouchInside };

// How two boundary triangles meet, beyond the nodes they share. Each bounds its tet on its inner
// side (against its normal), so a crossing, a coplanar overlap with both tets on the same side,
// and a vertex or edge of one touching the interior of the other from its inner side all put
// points of both tets' interiors together: an overlap of positive volume.
Contact classify(const Triangle& f, const Triangle& g) {
  const double tol = std::max(f.tol, g.tol);
  std::array<bool, 3> f_shared{}, g_shared{};
  int shared = 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (f.node[i] == g.node[j]) {
        f_shared[i] = g_shared[j] = true;
        ++shared;
      }
    }
  }
  if (shared == 3) return Contact::kNone;  // one face of two tets: validate_and_orient's case
  // Sides of the corners of each against the other's plane (a shared node lies on it).
  std::array<int, 3> sf{}, sg{};
  int f_pos = 0, f_neg = 0, g_pos = 0, g_neg = 0;
  int f_touch = 0, g_touch = 0;  // corners on the other's plane that are not shared
  for (int k = 0; k < 3; ++k) {
    sf[k] = f_shared[k] ? 0 : sign(g.distance(f.p[k]), tol);
    sg[k] = g_shared[k] ? 0 : sign(f.distance(g.p[k]), tol);
    f_pos += sf[k] > 0;
    f_neg += sf[k] < 0;
    g_pos += sg[k] > 0;
    g_neg += sg[k] < 0;
    f_touch += !f_shared[k] && sf[k] == 0;
    g_touch += !g_shared[k] && sg[k] == 0;
  }
  if (f_pos == 3 || f_neg == 3 || g_pos == 3 || g_neg == 3) return Contact::kNone;
  const double longest = std::max(f.longest, g.longest);
  if (f_pos + f_neg == 0 || g_pos + g_neg == 0) {
    // In one plane: an overlap with both tets on one side; from opposite sides they touch.
    if (f.normal.dot(g.normal) > 0 && overlap_area(f, g, tol) > tol * longest)
      return Contact::kCoplanar;
    return Contact::kNone;
  }
  if (f_pos > 0 && f_neg > 0 && g_pos > 0 && g_neg > 0) {
    // Each crosses the other's plane: the segments where they do lie on the planes' common line;
    // the triangles cross where these overlap.
    const Vec3 line = f.normal.cross(g.normal).normalized();
    const auto interval = [&](const Triangle& t, const std::array<int, 3>& s,
                              const Triangle& other) {
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      const auto add = [&](const Vec3& x) {
        lo = std::min(lo, line.dot(x));
        hi = std::max(hi, line.dot(x));
      };
      for (int k = 0; k < 3; ++k) {
        const int l = (k + 1) % 3;
        if (s[k] == 0) add(t.p[k]);
        if (s[k] * s[l] < 0) {
          const double dk = other.distance(t.p[k]), dl = other.distance(t.p[l]);
          add(t.p[k] + (t.p[l] - t.p[k]) * (dk / (dk - dl)));
        }
      }
      return std::pair{lo, hi};
    };
    const auto [f_lo, f_hi] = interval(f, sf, g);
    const auto [g_lo, g_hi] = interval(g, sg, f);
    return std::min(f_hi, g_hi) - std::max(f_lo, g_lo) > tol ? Contact::kCross : Contact::kNone;
  }
  // One lies on one side of the other's plane and touches it in a corner or an edge (beyond the
  // nodes they share, which lie on the other's boundary): an overlap when it does so inside the
  // other's interior from the other's inner side.
  const auto touches_inside = [&](const Triangle& t, const std::array<int, 3>& s, int neg, int pos,
                                  int touch, const Triangle& other) {
    if (neg == 0 || pos > 0 || touch == 0) return false;
    int on[2], count = 0;
    for (int k = 0; k < 3; ++k)
      if (s[k] == 0) on[count++] = k;
    return count > 0 && enters_interior(other, t.p[on[0]], t.p[on[count - 1]], tol);
  };
  if (touches_inside(f, sf, f_neg, f_pos, f_touch, g) ||
      touches_inside(g, sg, g_neg, g_pos, g_touch, f))
    return Contact::kTouchInside;
  return Contact::kNone;
}

// Signed solid angle of triangle g seen from p, positive from its inner side (Van Oosterom and
// Strackee 1983): with a, b, c its corners relative to p,
//   tan(Omega / 2) = a.(b x c) / (|a||b||c| + (a.b)|c| + (b.c)|a| + (c.a)|b|).
// A p on g's interior (g in the plane of the triangle f whose centroid p is, touching it) gives
// the limit from f's inner side: 2 pi if g faces the way f does, -2 pi if not.
double solid_angle(const Triangle& g, const Vec3& p, const Vec3& f_normal) {
  const Vec3 a = g.p[0] - p, b = g.p[1] - p, c = g.p[2] - p;
  const double la = a.norm(), lb = b.norm(), lc = c.norm();
  const double num = a.dot(b.cross(c));
  const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
  if (std::abs(num) <= kRelativeTolerance * la * lb * lc && den < 0)
    return g.normal.dot(f_normal) >= 0 ? 2 * std::numbers::pi : -2 * std::numbers::pi;
  return 2 * std::atan2(num, den);
}

// The boundary triangles of the body (the faces without a neighbour, ordered by tet and face as
// boundary_faces orders them), with their tolerances.
std::vector<Triangle> boundary_triangles(const TetMesh& mesh, const TetIndices& neighbours) {
  std::vector<Triangle> out;
  const auto add = [&](Index tet, const std::array<Index, 3>& node) {
    Triangle& t = out.emplace_back();
    double magnitude = 0;
    for (int k = 0; k < 3; ++k) {
      t.node[k] = node[k];
      t.p[k] = mesh.X.row(node[k]);
      magnitude = std::max(magnitude, t.p[k].cwiseAbs().maxCoeff());
    }
    t.normal = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).normalized();
    t.longest =
        std::max({(t.p[1] - t.p[0]).norm(), (t.p[2] - t.p[1]).norm(), (t.p[0] - t.p[2]).norm()});
    t.tol = kRelativeTolerance * t.longest + kRoundingFloor * magnitude;
    t.tet = tet;
  };
  if (neighbours.rows() == mesh.tets.rows()) {
    for (Index t = 0; t < mesh.tets.rows(); ++t)
      for (int k = 0; k < 4; ++k)
        if (neighbours(t, k) < 0)
          add(t, {mesh.tets(t, kTetFace[k][0]), mesh.tets(t, kTetFace[k][1]),
                  mesh.tets(t, kTetFace[k][2])});
  } else {
    const BoundaryFaces faces = boundary_faces(mesh.tets);
    for (Index f = 0; f < faces.tris.rows(); ++f)
      add(faces.tet(f), {faces.tris(f, 0), faces.tris(f, 1), faces.tris(f, 2)});
  }
  return out;
}

// "(a b c)": the file's numbers of the nodes of triangle t.
std::string face_name(const MeshSource& source, const Triangle& t) {
  return "(" + std::to_string(source.file_node(t.node[0])) + " " +
         std::to_string(source.file_node(t.node[1])) + " " +
         std::to_string(source.file_node(t.node[2])) + ")";
}

// Step 1: no two boundary triangles cross, overlap in a plane or touch from inside.
void check_pairs(const std::vector<Triangle>& tris, const MeshSource& source) {
  std::vector<Box> boxes(tris.size());
  for (size_t f = 0; f < tris.size(); ++f) {
    for (const Vec3& p : tris[f].p) boxes[f].add(p);
    boxes[f].lo.array() -= tris[f].tol;
    boxes[f].hi.array() += tris[f].tol;
  }
  Index bad_f = -1, bad_g = -1;
  Contact bad = Contact::kNone;
  BoxTree(boxes).for_each_meeting_pair([&](Index f, Index g) {
    bad = classify(tris[f], tris[g]);
    if (bad == Contact::kNone) return true;
    bad_f = f, bad_g = g;
    return false;
  });
  if (bad == Contact::kNone) return;
  // Name the later element first: an element added to a valid mesh comes last.
  const Triangle *later = &tris[bad_f], *earlier = &tris[bad_g];
  if (later->tet < earlier->tet) std::swap(later, earlier);
  const std::string how = bad == Contact::kCross ? "cross"
                          : bad == Contact::kCoplanar
                              ? "overlap in one plane with both elements on the same side"
                              : "touch, one inside the other's element";
  throw InputError(located(source.file, source.line_of_tet(later->tet),
                           source.element_name(later->tet) + " overlaps " +
                               source.element_name(earlier->tet) + ": their boundary faces " +
                               face_name(source, *later) + " and " + face_name(source, *earlier) +
                               " " + how));
}

// Whether p lies inside tet t (deeper than a small fraction of its barycentric coordinates).
bool tet_holds(const TetMesh& mesh, Index t, const Vec3& p) {
  std::array<Vec3, 4> x;
  for (int k = 0; k < 4; ++k) x[k] = mesh.X.row(mesh.tets(t, k));
  const double whole = signed_volume(x[0], x[1], x[2], x[3]);
  for (int k = 0; k < 4; ++k) {
    std::array<Vec3, 4> y = x;
    y[k] = p;
    if (signed_volume(y[0], y[1], y[2], y[3]) <= 1e-9 * whole) return false;
  }
  return true;
}

// Steps 2 and 3: every triangle has w = 1 on its inner side and 0 on its outer side.
void check_winding(const TetMesh& mesh, const std::vector<Triangle>& tris,
                   const MeshSource& source) {
  const Index n = static_cast<Index>(tris.size());
  // Sides: 2 f is the inner side of triangle f, 2 f + 1 its outer side. A link from side s to t
  // says w(t) = w(s) + diff. Every side has four: to the other side of its triangle, and at each
  // of the triangle's edges to the side facing the same wedge of space.
  struct Link {
    Index to = -1;
    int diff = 0;
  };
  std::vector<Link> links(8 * static_cast<size_t>(n));
  std::vector<int> degree(2 * static_cast<size_t>(n), 0);
  const auto link = [&](Index s, Index t, int diff) {
    links[4 * static_cast<size_t>(s) + degree[s]++] = {t, diff};
    links[4 * static_cast<size_t>(t) + degree[t]++] = {s, -diff};
  };
  const auto inner = [](Index f) { return 2 * f; };
  const auto outer = [](Index f) { return 2 * f + 1; };
  for (Index f = 0; f < n; ++f) link(outer(f), inner(f), 1);

  // The triangles at each edge (lo, hi), grouped by lo (a counting sort), then by hi; `forward`:
  // the triangle runs along it from lo to hi.
  struct EdgeUse {
    Index hi, tri;
    int corner;  // the triangle's corner opposite the edge
    bool forward;
  };
  const Index num_nodes = static_cast<Index>(mesh.X.rows());
  std::vector<size_t> start(static_cast<size_t>(num_nodes) + 1, 0);
  for (const Triangle& t : tris)
    for (int k = 0; k < 3; ++k) ++start[std::min(t.node[k], t.node[(k + 1) % 3]) + 1];
  for (size_t i = 1; i < start.size(); ++i) start[i] += start[i - 1];
  std::vector<EdgeUse> uses(3 * static_cast<size_t>(n));
  {
    std::vector<size_t> next(start.begin(), start.end() - 1);
    for (Index f = 0; f < n; ++f) {
      for (int k = 0; k < 3; ++k) {
        const Index a = tris[f].node[k], b = tris[f].node[(k + 1) % 3];
        uses[next[std::min(a, b)]++] = {std::max(a, b), f, (k + 2) % 3, a < b};
      }
    }
  }
  std::vector<std::pair<double, const EdgeUse*>> around;
  for (Index lo = 0; lo < num_nodes; ++lo) {
    const auto first = uses.begin() + static_cast<std::ptrdiff_t>(start[lo]);
    const auto last = uses.begin() + static_cast<std::ptrdiff_t>(start[lo + 1]);
    std::sort(first, last, [](const EdgeUse& x, const EdgeUse& y) {
      return x.hi != y.hi ? x.hi < y.hi : x.tri < y.tri;
    });
    for (auto i = first; i != last;) {
      auto j = i + 1;
      while (j != last && j->hi == i->hi) ++j;
      if (j - i == 2 && i->forward != (i + 1)->forward) {
        // An edge of two: the tets lie between them.
        link(inner(i->tri), inner((i + 1)->tri), 0);
        link(outer(i->tri), outer((i + 1)->tri), 0);
      } else if (j - i >= 2) {
        // Triangles in angle around the edge (right-handed about lo -> hi): between neighbours
        // lies one wedge of space. A forward triangle's normal points the way the angle grows.
        const Vec3 origin = mesh.X.row(lo);
        const Vec3 axis = (Vec3(mesh.X.row(i->hi)) - origin).normalized();
        Eigen::Index smallest = 0;
        axis.cwiseAbs().minCoeff(&smallest);
        const Vec3 e1 = axis.cross(Vec3::Unit(smallest)).normalized(), e2 = axis.cross(e1);
        around.clear();
        for (auto k = i; k != j; ++k) {
          const Vec3 r = tris[k->tri].p[k->corner] - origin;
          around.push_back({std::atan2(r.dot(e2), r.dot(e1)), &*k});
        }
        std::ranges::sort(around, [](const auto& x, const auto& y) {
          return x.first != y.first ? x.first < y.first : x.second->tri < y.second->tri;
        });
        for (size_t k = 0; k < around.size(); ++k) {
          const EdgeUse& a = *around[k].second;
          const EdgeUse& b = *around[(k + 1) % around.size()].second;
          link(a.forward ? outer(a.tri) : inner(a.tri), b.forward ? inner(b.tri) : outer(b.tri), 0);
        }
      }
      i = j;
    }
  }
  const auto links_of = [&](Index s) {
    return std::span<const Link>(links.data() + 4 * static_cast<size_t>(s),
                                 static_cast<size_t>(degree[s]));
  };

  // Groups of linked sides (both sides of a triangle are in one), their triangles and boxes.
  std::vector<Index> group(2 * static_cast<size_t>(n), -1);
  std::vector<std::vector<Index>> members;
  std::vector<Box> group_box;
  std::vector<Index> stack;
  for (Index f = 0; f < n; ++f) {
    if (group[inner(f)] >= 0) continue;
    const Index id = static_cast<Index>(members.size());
    members.emplace_back();
    group_box.emplace_back();
    group[inner(f)] = id;
    stack.assign(1, inner(f));
    while (!stack.empty()) {
      const Index s = stack.back();
      stack.pop_back();
      if (s % 2 == 0) {
        members[id].push_back(s / 2);
        for (const Vec3& p : tris[s / 2].p) group_box[id].add(p);
      }
      for (const Link& l : links_of(s)) {
        if (group[l.to] < 0) {
          group[l.to] = id;
          stack.push_back(l.to);
        }
      }
    }
  }
  for (std::vector<Index>& m : members) std::ranges::sort(m);
  const BoxTree groups(group_box);

  // w just inside triangle f: 1/2 from f itself, and the solid angles of the triangles of every
  // group whose box holds f's centroid (a closed group adds nothing outside its box).
  const auto winding_inside = [&](Index f) {
    const Vec3 c = tris[f].centroid();
    double sum = 0;
    groups.for_each_holding(c, [&](Index id) {
      for (const Index g : members[id])
        if (g != f) sum += solid_angle(tris[g], c, tris[f].normal);
    });
    return 0.5 + sum / (4 * std::numbers::pi);
  };

  std::vector<int> value(2 * static_cast<size_t>(n), INT_MIN);
  Index worst = -1;  // a triangle whose sides are wrong, the one of the latest tet
  bool conflict = false;
  const auto flag = [&](Index f, bool from_conflict) {
    if (worst < 0 || tris[f].tet > tris[worst].tet) {
      worst = f;
      conflict = from_conflict;
    }
  };
  for (const std::vector<Index>& m : members) {
    // Evaluate w at the first triangle whose centroid gives a clear integer (at most 8 tried).
    double w = winding_inside(m.front());
    for (size_t k = 1; k < std::min<size_t>(m.size(), 8) && std::abs(w - std::round(w)) > 0.1;
         ++k) {
      const double again = winding_inside(m[k]);
      if (std::abs(again - std::round(again)) < std::abs(w - std::round(w))) w = again;
    }
    value[inner(m.front())] = static_cast<int>(std::lround(w));
    stack.assign(1, inner(m.front()));
    while (!stack.empty()) {
      const Index s = stack.back();
      stack.pop_back();
      for (const Link& l : links_of(s)) {
        const Index t = l.to;
        const int expected = value[s] + l.diff;
        if (value[t] == INT_MIN) {
          value[t] = expected;
          stack.push_back(t);
        } else if (value[t] != expected) {
          flag(t / 2, true);
        }
      }
    }
    for (const Index f : m)
      if (value[inner(f)] != 1) flag(f, false);
  }
  if (worst < 0) return;

  const Triangle& bad = tris[worst];
  const Index t = bad.tet;
  // Name an element that holds a point of t next to the face, or t's centroid.
  Vec3 centre = Vec3::Zero();
  for (int k = 0; k < 4; ++k) centre += mesh.X.row(mesh.tets(t, k)).transpose() / 4;
  const Vec3 near_face = bad.centroid() + 1e-3 * (centre - bad.centroid());
  std::string other = "other elements";
  for (Index u = 0; u < mesh.tets.rows(); ++u) {
    if (u != t && (tet_holds(mesh, u, near_face) || tet_holds(mesh, u, centre))) {
      other = source.element_name(u);
      break;
    }
  }
  const std::string why =
      conflict ? "the space around its boundary face " + face_name(source, bad) +
                     " is covered a different number of times seen from different edges"
               : "the space just inside its boundary face " + face_name(source, bad) +
                     " is covered by " + std::to_string(value[inner(worst)]) + " elements";
  throw InputError(located(source.file, source.line_of_tet(t),
                           source.element_name(t) + " overlaps " + other + ": " + why));
}

}  // namespace

void check_no_overlap(const TetMesh& mesh, const MeshSource& source, const TetIndices& neighbours) {
  const std::vector<Triangle> tris = boundary_triangles(mesh, neighbours);
  check_pairs(tris, source);
  check_winding(mesh, tris, source);
}

}  // namespace depthfem
