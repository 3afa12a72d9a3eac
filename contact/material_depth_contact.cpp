#include "contact/material_depth_contact.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <functional>
#include <numeric>
#include <stdexcept>

#include "contact/contact_surface.hpp"
#include "contact/penalty.hpp"
#include "core/mass.hpp"

namespace depthfem {

namespace {
constexpr Index kChunk = 256;  // triangles per task of the pair search

std::array<Vec3, 4> tet_corners(const Points& x, const TetIndices& tets, Index t) {
  return {x.row(tets(t, 0)), x.row(tets(t, 1)), x.row(tets(t, 2)), x.row(tets(t, 3))};
}
std::array<Vec3, 3> tri_corners(const Points& x, const TriIndices& tris, Index f) {
  return {x.row(tris(f, 0)), x.row(tris(f, 1)), x.row(tris(f, 2))};
}

// Whether tet t and triangle f share a node.
bool shares_node(const TetIndices& tets, Index t, const TriIndices& tris, Index f) {
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 3; ++b)
      if (tets(t, a) == tris(f, b)) return true;
  return false;
}

// Fills the compressed rows (start, values) of n rows in parallel over chunks of rows, row(i,
// out) appending row i's values to out.
template <class Row>
void fill_rows(Index n, Row&& row, std::vector<Index>& start, std::vector<Index>& values) {
  const Index chunks = (n + kChunk - 1) / kChunk;
  std::vector<std::vector<Index>> parts(static_cast<size_t>(chunks));
  start.assign(static_cast<size_t>(n) + 1, 0);
  tbb::parallel_for(Index(0), chunks, [&](Index c) {
    std::vector<Index>& part = parts[static_cast<size_t>(c)];
    for (Index i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) {
      const size_t before = part.size();
      row(i, part);
      start[static_cast<size_t>(i) + 1] = static_cast<Index>(part.size() - before);
    }
  });
  std::partial_sum(start.begin(), start.end(), start.begin());
  values.clear();
  values.reserve(static_cast<size_t>(start.back()));
  for (const std::vector<Index>& part : parts)
    values.insert(values.end(), part.begin(), part.end());
}

// True when some fan triangle of the polygon counts (fan_triangle_counts). A polygon without one
// (a triangle touching a tet along an edge or at a point, as where bodies rest on each other)
// adds nothing to the energy or its derivatives, so it is not kept as a pair: it would only
// cost clipping, integration and couplings in the Hessian pattern.
bool has_area(const ClipPolygon& poly, double min_area2) {
  for (int k = 1; k + 1 < poly.size; ++k) {
    const Vec3 c = (poly.x[k] - poly.x[0]).cross(poly.x[k + 1] - poly.x[0]);
    if (fan_triangle_counts(c.squaredNorm(), min_area2)) return true;
  }
  return false;
}
}  // namespace

MaterialDepthContact::MaterialDepthContact(const Mesh& mesh, VectorX depth, ContactOptions options,
                                           ContactPart part)
    : tets_(mesh.tets),
      tris_(mesh.tris),
      tet_body_(mesh.tet_body),
      tri_body_(mesh.tri_body),
      depth_(std::move(depth)),
      options_(options),
      bodies_(mesh.bodies),
      interfaces_(mesh.bodies, options.self_contact),
      part_(std::move(part)) {
  // Sub-triangles with area below 1e-12 of a typical element face count as degenerate.
  const double h = mean_edge_length(mesh.X, mesh.tets);
  min_area2_ = std::pow(1e-12 * h * h, 2);
  margin_ = options_.list_margin * h;
  for (const Body& b : bodies_) {
    std::vector<Index>& own = tree_tets_.emplace_back();
    for (Index t = b.first_tet; t < b.first_tet + b.num_tets; ++t)
      if (part_.owned.empty() || part_.owned[static_cast<size_t>(t)]) own.push_back(t);
  }
  build_trees(mesh.X);
}

std::vector<Box3> MaterialDepthContact::tree_boxes(const std::vector<Box3>& boxes, size_t b) const {
  std::vector<Box3> out(tree_tets_[b].size());
  for (size_t k = 0; k < out.size(); ++k) out[k] = boxes[static_cast<size_t>(tree_tets_[b][k])];
  return out;
}

void MaterialDepthContact::build_trees(const Points& x) {
  const std::vector<Box3> boxes = tet_boxes(x, tets_);
  trees_.clear();
  walk_rank_.assign(static_cast<size_t>(tets_.rows()), -1);
  for (size_t b = 0; b < bodies_.size(); ++b) {
    const std::vector<Index> order = trees_.emplace_back(tree_boxes(boxes, b)).walk_order();
    for (size_t k = 0; k < order.size(); ++k)
      walk_rank_[static_cast<size_t>(tree_tets_[b][static_cast<size_t>(order[k])])] =
          static_cast<Index>(k);
  }
}

std::vector<Box3> MaterialDepthContact::refit_to_listed(const std::vector<Box3>& boxes) {
  for (size_t b = 0; b < bodies_.size(); ++b) trees_[b].refit(tree_boxes(boxes, b));
  // Boxes grown by the margin each overlap where the triangle's, grown by twice it, overlaps.
  return triangle_boxes(listed_x_, tris_, 2 * margin_);
}

void MaterialDepthContact::search(Index f, const Box3& grown, std::vector<Index>& out) const {
  const Index body = tri_body_(f);
  for (Index other = 0; other < static_cast<Index>(bodies_.size()); ++other) {
    if (!searched(body, other)) continue;
    trees_[other].query(grown, [&](Index local) {
      const Index t = tree_tets_[static_cast<size_t>(other)][static_cast<size_t>(local)];
      if (!neighbours(f, t)) out.push_back(t);
    });
  }
}

bool MaterialDepthContact::neighbours(Index f, Index t) const {
  return tri_body_(f) == tet_body_(t) && shares_node(tets_, t, tris_, f);
}

bool MaterialDepthContact::pairable(Index f, Index t) const {
  return searched(tri_body_(f), tet_body_(t)) && !neighbours(f, t);
}

void MaterialDepthContact::list_candidates(const std::vector<Box3>& boxes) {
  const std::vector<Box3> grown = refit_to_listed(boxes);
  fill_rows(
      static_cast<Index>(tris_.rows()),
      [&](Index f, std::vector<Index>& out) { search(f, grown[static_cast<size_t>(f)], out); },
      listed_.start, listed_.tets);
  stats_.searched_triangles = static_cast<Index>(tris_.rows());
}

void MaterialDepthContact::update_candidates(const std::vector<Index>& moved,
                                             const std::vector<Box3>& boxes) {
  std::vector<char> node_moved(static_cast<size_t>(listed_x_.rows()), 0);
  for (Index i : moved) node_moved[static_cast<size_t>(i)] = 1;
  const auto touches = [&](const auto& elements, Index e) {
    for (Eigen::Index k = 0; k < elements.cols(); ++k)
      if (node_moved[static_cast<size_t>(elements(e, k))]) return true;
    return false;
  };
  const std::vector<Box3> grown = refit_to_listed(boxes);
  // The tree tets with a moved node, and the triangles without one whose grown boxes theirs
  // now meet: each such triangle's list loses the moved tets and gains those it meets.
  const AabbTree triangles(grown);
  std::vector<char> tri_moved(static_cast<size_t>(tris_.rows()));
  std::vector<char> tet_moved(static_cast<size_t>(tets_.rows()), 0);
  for (Index f = 0; f < static_cast<Index>(tris_.rows()); ++f)
    tri_moved[static_cast<size_t>(f)] = touches(tris_, f);
  std::vector<std::pair<Index, Index>> met;  // (triangle, tet)
  for (const std::vector<Index>& own : tree_tets_)
    for (Index t : own) {
      if (!touches(tets_, t)) continue;
      tet_moved[static_cast<size_t>(t)] = 1;
      triangles.query(boxes[static_cast<size_t>(t)], [&](Index f) {
        if (!tri_moved[static_cast<size_t>(f)] && pairable(f, t)) met.emplace_back(f, t);
      });
    }
  std::ranges::sort(met);
  // A search of the trees visits a triangle's tets body by body, each tree in its walk order.
  const auto walked_before = [&](Index a, Index b) {
    return std::pair(tet_body_(a), walk_rank_[static_cast<size_t>(a)]) <
           std::pair(tet_body_(b), walk_rank_[static_cast<size_t>(b)]);
  };
  const CandidateList old = std::move(listed_);
  fill_rows(
      static_cast<Index>(tris_.rows()),
      [&](Index f, std::vector<Index>& out) {
        if (tri_moved[static_cast<size_t>(f)]) {
          search(f, grown[static_cast<size_t>(f)], out);
          return;
        }
        const size_t first = out.size();
        for (Index k = old.start[static_cast<size_t>(f)]; k < old.start[static_cast<size_t>(f) + 1];
             ++k)
          if (!tet_moved[static_cast<size_t>(old.tets[static_cast<size_t>(k)])])
            out.push_back(old.tets[static_cast<size_t>(k)]);
        // met is sorted by triangle, then tet: (f, -1) comes before f's first.
        auto it = std::lower_bound(met.begin(), met.end(), std::pair<Index, Index>(f, -1));
        if (it == met.end() || it->first != f) return;
        for (; it != met.end() && it->first == f; ++it) out.push_back(it->second);
        std::sort(out.begin() + static_cast<std::ptrdiff_t>(first), out.end(), walked_before);
      },
      listed_.start, listed_.tets);
  stats_.searched_triangles = std::ranges::count(tri_moved, 1);
}

bool MaterialDepthContact::searched(Index a, Index b) const {
  if (bodies_[a].rigid && bodies_[b].rigid) return false;
  const std::array<Index, 2> pair = {std::min(a, b), std::max(a, b)};
  if (std::ranges::find(options_.excluded, pair) != options_.excluded.end()) return false;
  return a != b || options_.self_contact;
}

std::array<Index, 7> MaterialDepthContact::pair_nodes(const ContactPair& p) const {
  return {tets_(p.tet, 0), tets_(p.tet, 1), tets_(p.tet, 2), tets_(p.tet, 3),
          tris_(p.tri, 0), tris_(p.tri, 1), tris_(p.tri, 2)};
}

void MaterialDepthContact::begin_step(const Points& x) {
  build_trees(x);
  listed_x_.resize(0, 3);
}

std::vector<ContactPair> MaterialDepthContact::clip(const Points& x, const std::vector<Box3>& boxes,
                                                    const CandidateList& list,
                                                    Index& candidates) const {
  const Index n = static_cast<Index>(tris_.rows());
  const Index chunks = (n + kChunk - 1) / kChunk;
  std::vector<std::vector<ContactPair>> found(static_cast<size_t>(chunks));
  std::vector<Index> tried(static_cast<size_t>(chunks), 0);
  tbb::parallel_for(Index(0), chunks, [&](Index c) {
    for (Index f = c * kChunk; f < std::min(n, (c + 1) * kChunk); ++f) {
      const std::array<Vec3, 3> Q = tri_corners(x, tris_, f);
      Box3 box;
      for (const Vec3& q : Q) box.extend(q);
      for (Index k = list.start[f]; k < list.start[f + 1]; ++k) {
        const Index t = list.tets[k];
        if (!boxes[t].intersects(box)) continue;
        ++tried[c];
        ClipPolygon poly = clip_triangle_by_tet(tet_corners(x, tets_, t), Q);
        if (poly.size >= 3 && has_area(poly, min_area2_)) found[c].push_back({f, t, poly});
      }
    }
  });
  std::vector<ContactPair> pairs;
  candidates = 0;
  for (Index c = 0; c < chunks; ++c) {
    pairs.insert(pairs.end(), found[c].begin(), found[c].end());
    candidates += tried[c];
  }
  return pairs;
}

void MaterialDepthContact::prepare(const Points& x) {
  stats_ = ContactStats{};
  std::vector<Index> moved;  // the nodes farther than the margin from where the list took them
  if (listed_x_.rows() == x.rows()) {
    for (Index i = 0; i < x.rows(); ++i)
      if ((x.row(i) - listed_x_.row(i)).squaredNorm() > margin_ * margin_) moved.push_back(i);
  }
  // An update touches the moved nodes' triangles and tets and passes over the whole list once;
  // past an eighth of the nodes a new list costs about as much (bench/results/knee.md).
  stats_.relisted = listed_x_.rows() != x.rows() || !moved.empty();
  const std::vector<Box3> boxes = tet_boxes(x, tets_);
  if (listed_x_.rows() != x.rows() || static_cast<Index>(moved.size()) > x.rows() / 8) {
    listed_x_ = x;
    list_candidates(boxes);
  } else if (!moved.empty()) {
    for (Index i : moved) listed_x_.row(i) = x.row(i);
    update_candidates(moved, tet_boxes(listed_x_, tets_));
  }
  std::vector<ContactPair> all = clip(x, boxes, listed_, stats_.candidates);
  stats_.listed = static_cast<Index>(listed_.tets.size());
  const Index n_pairs = static_cast<Index>(all.size());
  stats_.active = n_pairs;
  // Processing order: along a Morton curve through the polygons' centres, in colored chunks.
  PairSchedule::Nodes nodes(n_pairs, 7);
  Points centres(n_pairs, 3);
  for (Index k = 0; k < n_pairs; ++k) {
    const ContactPair& p = all[k];
    nodes.row(k) = Eigen::Map<const Eigen::Matrix<Index, 1, 7>>(pair_nodes(p).data());
    Vec3 centre = Vec3::Zero();
    for (int v = 0; v < p.polygon.size; ++v) centre += p.polygon.x[v];
    centres.row(k) = centre.transpose() / p.polygon.size;
  }
  const std::vector<Index> order =
      schedule_.arrange(nodes, centres, static_cast<Index>(depth_.size()), bound_);
  pairs_.resize(all.size());
  for (Index k = 0; k < n_pairs; ++k) pairs_[k] = all[order[k]];
  // A pair whose nodes are not coupled in the bound pattern needs a new one (bind() follows).
  pattern_changed_ = bound_ && !schedule_.has_blocks();
}

void MaterialDepthContact::add_couplings(SparsityBuilder& builder) const {
  schedule_.add_couplings(builder);
}

void MaterialDepthContact::bind(const BlockSparseMatrix& hessian) {
  bound_ = &hessian;
  pattern_changed_ = false;
  schedule_.bind(hessian, name());
}

std::array<double, 4> MaterialDepthContact::pair_depths(const ContactPair& p) const {
  return {depth_(tets_(p.tet, 0)), depth_(tets_(p.tet, 1)), depth_(tets_(p.tet, 2)),
          depth_(tets_(p.tet, 3))};
}

double MaterialDepthContact::pair_energy(const Points& x, const ContactPair& p) const {
  std::array<V3<double>, 4> P;
  std::array<V3<double>, 3> Q;
  for (int a = 0; a < 4; ++a) P[a] = make_point<double>(x.row(tets_(p.tet, a)), 0);
  for (int b = 0; b < 3; ++b) Q[b] = make_point<double>(x.row(tris_(p.tri, b)), 0);
  return tet_polygon_penalty(p.polygon, P, Q, pair_depths(p), options_.penalty, min_area2_);
}

double MaterialDepthContact::pair_derivatives(const Points& x, const ContactPair& p,
                                              PairGradient& gradient, PairHessian* hessian) const {
  return tet_polygon_penalty_derivatives(p.polygon, tet_corners(x, tets_, p.tet),
                                         tri_corners(x, tris_, p.tri), pair_depths(p),
                                         options_.penalty, min_area2_, gradient, hessian);
}

double MaterialDepthContact::evaluate(const Points& x, VectorX* gradient,
                                      BlockSparseMatrix* hessian) const {
  if (!gradient) return schedule_.run(0.0, [&](Index k) { return pair_energy(x, pairs_[k]); });
  if (hessian && !schedule_.has_blocks())
    throw std::logic_error("contact: bind() the Hessian after prepare() found new pairs");
  // Each pair's derivatives are added as soon as they are computed.
  return schedule_.run(0.0, [&](Index k) {
    PairGradient grad;
    PairHessian hess;
    const double energy = pair_derivatives(x, pairs_[k], grad, hessian ? &hess : nullptr);
    for (int a = 0; a < 7; ++a)
      gradient->segment<3>(3 * schedule_.node(k, a)) += grad.segment<3>(3 * a);
    if (hessian) hessian->add_blocks<7>(schedule_.blocks(k), hess);
    return energy;
  });
}

std::vector<ContactShare> MaterialDepthContact::shares(const Points& x) const {
  const Index n = static_cast<Index>(pairs_.size());
  std::vector<PairGradient> gradients(static_cast<size_t>(n));
  std::vector<double> energies(static_cast<size_t>(n));
  tbb::parallel_for(tbb::blocked_range<Index>(0, n, 16), [&](const tbb::blocked_range<Index>& r) {
    for (Index k = r.begin(); k < r.end(); ++k)
      energies[k] = pair_derivatives(x, pairs_[k], gradients[k], nullptr);
  });
  // One share per pair that presses, in processing order; merge() nets a triangle's pairs per
  // body it enters, so that splitting a triangle among tets adds no force: the in-plane pulls of
  // the pieces cancel.
  std::vector<ContactShare> out;
  for (Index k = 0; k < n; ++k) {
    const ContactPair& p = pairs_[k];
    // A polygon with zero depth everywhere (a surface resting on another, a bonded interface)
    // touches but does not press: no force, no contact area.
    if (!(energies[k] > 0)) continue;
    // The penalty pushes the triangle out of the tet: -grad W on the triangle's side.
    const Vec3 on_triangle = -gradients[k].tail<9>().reshaped(3, 3).rowwise().sum();
    // Material depth at the polygon's vertices: the tet's linear depth field g0 + a . (R - P0).
    std::array<V3<double>, 4> P;
    for (int a = 0; a < 4; ++a) P[a] = make_point<double>(x.row(tets_(p.tet, a)), 0);
    const std::array<double, 4> g = pair_depths(p);
    const V3<double> slope = depth_gradient(P, g);
    std::array<double, 8> G{};
    for (int j = 0; j < p.polygon.size; ++j)
      G[j] = g[0] + slope.dot(make_point<double>(p.polygon.x[j], 0) - P[0]);
    const PolygonMoments moments = polygon_moments(p.polygon, G);
    out.push_back({p.tri, tet_body_(p.tet), on_triangle, moments.area, moments.depth_integral});
  }
  return merge(out);
}

std::vector<ContactShare> MaterialDepthContact::merge(std::span<const ContactShare> shares) {
  std::vector<size_t> order(shares.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::ranges::stable_sort(order, {}, [&](size_t k) { return shares[k].tri; });
  std::vector<ContactShare> out;
  size_t first = 0;
  for (const size_t k : order) {
    const ContactShare& s = shares[k];
    if (first == out.size() || out[first].tri != s.tri) first = out.size();
    auto to = std::find_if(out.begin() + static_cast<std::ptrdiff_t>(first), out.end(),
                           [&](const ContactShare& o) { return o.body == s.body; });
    if (to == out.end()) {
      out.push_back(s);
    } else {
      to->force += s.force;
      to->area += s.area;
      to->depth_integral += s.depth_integral;
    }
  }
  return out;
}

void MaterialDepthContact::report_shares(std::span<const ContactShare> shares,
                                         StepRecord& step) const {
  ContactInterfaces::Tally tally = interfaces_.tally(step);
  step.surface.resize(static_cast<Index>(tris_.rows()));
  for (const ContactShare& s : shares) {
    add_to_surface(step.surface, s.tri, s.force, {s.area, s.depth_integral});
    tally.add(tri_body_(s.tri), s.body, s.force, s.area);
  }
  tally.finish();
}

void MaterialDepthContact::report(const Points& x, StepRecord& step) const {
  std::vector<ContactShare> own = shares(x);
  if (!part_.concatenate) return report_shares(own, step);
  // A distributed run's pairs are its own tets': every rank's shares, merged.
  std::vector<double> values;
  values.reserve(7 * own.size());
  for (const ContactShare& s : own)
    values.insert(values.end(), {double(s.tri), double(s.body), s.force.x(), s.force.y(),
                                 s.force.z(), s.area, s.depth_integral});
  const std::vector<double> all = part_.concatenate(values);
  std::vector<ContactShare> every(all.size() / 7);
  for (size_t k = 0; k < every.size(); ++k) {
    const double* v = all.data() + 7 * k;
    every[k] = {Index(v[0]), Index(v[1]), Vec3(v[2], v[3], v[4]), v[5], v[6]};
  }
  report_shares(merge(every), step);
}

}  // namespace depthfem
