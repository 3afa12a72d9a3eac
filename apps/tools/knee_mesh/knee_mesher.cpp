// Tetrahedral mesh of a knee from the BodyParts3D right-leg surfaces, written as Gmsh MSH 4.1
// with physical groups. Usage (see apps/scenes/knee/README.md for what it produces):
//
//   knee_mesher DATA_DIR OUT.msh [--size H] [--min-size H] [--gap-factor F] [--work DIR]
//               [--stats FILE.md]
//
// 1. CGAL Mesh_3 meshes a labelled domain whose labels come from inside-tests against the
//    full-resolution OBJ surfaces (bones first, then the soft tissue inside the skin), cropped to
//    z in [270, 590] mm. The crop's cut curves are protected as features so that the cut faces
//    stay planar. Tibia and fibula form one label (one rigid body); thin soft tissue between them
//    becomes bone, thin soft tissue between femur and tibia or femur and patella becomes empty
//    joint space. The curves where the joint space meets a bone are protected too, so that the
//    bone surfaces stay smooth there. The size field shrinks to the local gap width near the
//    joints, so that bones facing each other across a gap never share a vertex.
// 2. Every label is then improved on its own by TetGen (-rYq1.5/15: reconstruct the label's mesh,
//    keep its boundary triangles unchanged, add interior points for quality), so interfaces
//    between labels still coincide node for node.
// 3. The labels become physical volumes, and the boundary triangles physical surfaces: the
//    interfaces between soft tissue and each bone, the cut sections, the skin and the joint space.
//
// Deterministic: the mesher runs sequentially with CGAL's fixed default seed, TetGen is
// deterministic, and every container is iterated in a fixed order.

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_domain_with_polyline_features_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Polygon_mesh_processing/bbox.h>
#include <CGAL/Polygon_mesh_slicer.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/make_mesh_3.h>

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
using Primitive = CGAL::AABB_face_graph_triangle_primitive<SurfaceMesh>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
using Inside = CGAL::Side_of_triangle_mesh<SurfaceMesh, K>;

using Labeled = CGAL::Labeled_mesh_domain_3<K>;
using Domain = CGAL::Mesh_domain_with_polyline_features_3<Labeled>;
using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr, Domain::Corner_index, Domain::Curve_index>;
using Criteria = CGAL::Mesh_criteria_3<Tr>;

struct Fail : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Labels of the domain; 0 is outside (beyond the skin, beyond the crop, or joint space).
enum Label : int { kOutside = 0, kFemur = 1, kTibia = 2, kPatella = 3, kSoftTissue = 4 };
constexpr int kNumLabels = 4;
const char* const kLabelName[] = {"outside", "femur", "tibia", "patella", "soft_tissue"};

// Crop of the leg [mm]: single-loop cut sections, nearly symmetric about the flexion axis.
constexpr double kZLow = 270, kZHigh = 590;

struct Options {
  std::string data_dir, out, work = "knee_mesh_work", stats;
  double size = 9.5;         // largest edge length target [mm]
  double min_size = 1.0;     // smallest edge length target [mm]
  double gap_factor = 1.0;   // edge length near a joint = gap_factor x local gap width
  double joint_width = 5.0;  // soft tissue thinner than this between femur and tibia/patella is
                             // joint space [mm]
  double merge_width = 1.5;  // soft tissue thinner than this between tibia and fibula is bone [mm]
  double facet_distance = 0.6;  // surface approximation [mm] (bounded by gap / 3 near joints)
};

// A closed triangle surface with an inside test and distance queries.
struct Surface {
  std::string name;
  SurfaceMesh mesh;
  std::unique_ptr<Tree> tree;
  std::unique_ptr<Inside> inside;

  bool contains(const Point& p) const { return (*inside)(p) != CGAL::ON_UNBOUNDED_SIDE; }
  double distance(const Point& p) const { return std::sqrt(tree->squared_distance(p)); }
};

std::unique_ptr<Surface> read_obj(const std::string& path, const std::string& name) {
  std::ifstream in(path);
  if (!in) throw Fail(path + ": cannot open");
  auto s = std::make_unique<Surface>();
  s->name = name;
  std::vector<SurfaceMesh::Vertex_index> v;
  std::string line;
  long line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    std::istringstream ls(line);
    std::string key;
    ls >> key;
    if (key == "v") {
      double x, y, z;
      if (!(ls >> x >> y >> z)) throw Fail(path + ":" + std::to_string(line_no) + ": bad vertex");
      v.push_back(s->mesh.add_vertex(Point(x, y, z)));
    } else if (key == "f") {
      std::array<long, 3> f;
      for (long& i : f) {
        std::string tok;
        if (!(ls >> tok)) throw Fail(path + ":" + std::to_string(line_no) + ": bad face");
        i = std::stol(tok.substr(0, tok.find('/'))) - 1;
        if (i < 0 || i >= static_cast<long>(v.size()))
          throw Fail(path + ":" + std::to_string(line_no) + ": face index out of range");
      }
      if (s->mesh.add_face(v[f[0]], v[f[1]], v[f[2]]) == SurfaceMesh::null_face())
        throw Fail(path + ":" + std::to_string(line_no) + ": non-manifold face");
    }
  }
  if (!CGAL::is_closed(s->mesh)) throw Fail(path + ": surface is not closed");
  s->tree = std::make_unique<Tree>(faces(s->mesh).first, faces(s->mesh).second, s->mesh);
  s->tree->accelerate_distance_queries();
  s->inside = std::make_unique<Inside>(*s->tree);
  return s;
}

struct Anatomy {
  std::unique_ptr<Surface> femur, tibia, fibula, patella, skin;
  Options opt;

  // Label of a point: bones first, then the soft tissue inside the skin, except thin joint space.
  int label(const Point& p) const {
    if (p.z() < kZLow || p.z() > kZHigh) return kOutside;
    if (femur->contains(p)) return kFemur;
    if (tibia->contains(p) || fibula->contains(p)) return kTibia;
    if (patella->contains(p)) return kPatella;
    if (!skin->contains(p)) return kOutside;
    const double w = std::max(opt.joint_width, opt.merge_width);
    const double d_femur = femur->distance(p);
    const double d_tibia = tibia->distance(p);
    const double d_fibula = fibula->distance(p);
    if (d_tibia + d_fibula < opt.merge_width) return kTibia;
    if (d_femur < w) {
      if (d_femur + std::min(d_tibia, d_fibula) < opt.joint_width) return kOutside;
      if (d_femur + patella->distance(p) < opt.joint_width) return kOutside;
    }
    return kSoftTissue;
  }

  // Narrowest gap between two bones through p [mm] (the sum of the distances to both).
  double gap(const Point& p) const {
    const double d_femur = femur->distance(p);
    const double d_tibia = std::min(tibia->distance(p), fibula->distance(p));
    return std::min(d_femur + d_tibia, d_femur + patella->distance(p));
  }
};

// A field growing with the local gap width between bones: clamp(factor x gap, lo, hi) [mm].
struct GapField {
  const Anatomy* anatomy;
  double factor, lo, hi;
  template <class Index>
  double operator()(const Point& p, int, const Index&) const {
    return std::clamp(factor * anatomy->gap(p), lo, hi);
  }
};

// Closed polylines where the plane z = height cuts a surface.
void add_cut_curves(const Surface& s, double height, std::vector<std::vector<Point>>& out) {
  CGAL::Polygon_mesh_slicer<SurfaceMesh, K> slicer(s.mesh);
  std::vector<std::vector<Point>> loops;
  slicer(K::Plane_3(0, 0, 1, -height), std::back_inserter(loops));
  for (std::vector<Point>& loop : loops) {
    if (loop.size() < 4) continue;
    if (loop.front() != loop.back()) loop.push_back(loop.front());
    // Put every point exactly on the plane (the slicer interpolates along edges).
    for (Point& q : loop) q = Point(q.x(), q.y(), height);
    out.push_back(std::move(loop));
  }
}

// Closed polylines on the surface `s` where the distance to the nearest of `others` equals
// `width`: where the wall of the joint space (Anatomy::label) meets the bone. Bone, soft tissue
// and joint space meet there, the tissue and the joint space each in a wedge of about 90 degrees.
// Left to Delaunay refinement, such a curve is not resolved: vertices land on the wall beside the
// bone and bone tets reach out along it as fins into the tissue (the knee's femur had fins up to
// 1.7 mm high, the normals of adjacent bone triangles up to 125 degrees apart). Protected as a
// feature, the curve becomes mesh edges whose vertices lie on both the bone and the wall. The
// points are the roots of the distance along the surface's edges (bisection), joined across its
// faces.
void add_wall_curves(const Surface& s, const std::vector<const Surface*>& others, double width,
                     std::vector<std::vector<Point>>& out) {
  const SurfaceMesh& m = s.mesh;
  const auto f = [&](const Point& p) {
    double d = 1e300;
    for (const Surface* o : others) d = std::min(d, o->distance(p));
    return d - width;
  };
  std::vector<double> f_vertex(m.number_of_vertices());
  for (const auto v : vertices(m)) f_vertex[v] = f(m.point(v));
  const auto inside = [&](SurfaceMesh::Vertex_index v) { return f_vertex[v] < 0; };
  const auto crosses = [&](SurfaceMesh::Halfedge_index h) {
    return inside(source(h, m)) != inside(target(h, m));
  };
  const auto root = [&](SurfaceMesh::Halfedge_index h) {
    const bool source_inside = inside(source(h, m));
    Point in = m.point(source_inside ? source(h, m) : target(h, m));
    Point off = m.point(source_inside ? target(h, m) : source(h, m));
    for (int k = 0; k < 50; ++k) {
      const Point mid = CGAL::midpoint(in, off);
      (f(mid) < 0 ? in : off) = mid;
    }
    return CGAL::midpoint(in, off);
  };
  // A face with a crossing edge has exactly two; walking from one to the other and on into the
  // next face closes a loop (the surface is closed).
  std::vector<char> visited(m.number_of_edges(), 0);
  for (const auto e : edges(m)) {
    if (visited[e] || !crosses(halfedge(e, m))) continue;
    std::vector<Point> loop;
    SurfaceMesh::Halfedge_index h = halfedge(e, m);
    do {
      visited[edge(h, m)] = 1;
      loop.push_back(root(h));
      SurfaceMesh::Halfedge_index n = next(h, m);
      if (!crosses(n)) n = next(n, m);
      h = opposite(n, m);
    } while (edge(h, m) != e);
    for (const Point& p : loop)
      if (p.z() < kZLow || p.z() > kZHigh)
        throw Fail("the joint space wall on the " + s.name + " leaves the crop");
    loop.push_back(loop.front());
    out.push_back(std::move(loop));
  }
}

// ---------------------------------------------------------------------------------------------
// Flexion axis: the geometric centre axis, the line through the centres of spheres fitted to the
// posterior surfaces of the two femoral condyles.

struct Axis {
  Eigen::Vector3d center, direction;       // midpoint of the sphere centres; lateral -> medial (+x)
  std::array<Eigen::Vector4d, 2> spheres;  // lateral, medial: centre and radius [mm]
};

// Algebraic least-squares sphere: |p|^2 = 2 c.p + (r^2 - |c|^2), linear in c and r^2 - |c|^2.
Eigen::Vector4d fit_sphere(const std::vector<Eigen::Vector3d>& points) {
  Eigen::MatrixXd A(points.size(), 4);
  Eigen::VectorXd b(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    A.row(i) << 2 * points[i].transpose(), 1.0;
    b(i) = points[i].squaredNorm();
  }
  const Eigen::Vector4d q = A.colPivHouseholderQr().solve(b);
  const Eigen::Vector3d c = q.head<3>();
  return {c.x(), c.y(), c.z(), std::sqrt(q(3) + c.squaredNorm())};
}

// The condyles are the femur's vertices within 35 mm of its lowest point; their posterior half
// (behind the middle of their y range) is split at the middle of their x range into the lateral
// (-x) and medial (+x) condyle.
Axis flexion_axis(const Surface& femur) {
  std::vector<Eigen::Vector3d> all;
  for (const auto v : vertices(femur.mesh)) {
    const Point& p = femur.mesh.point(v);
    all.emplace_back(p.x(), p.y(), p.z());
  }
  double z_min = 1e300;
  for (const auto& p : all) z_min = std::min(z_min, p.z());
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  std::vector<Eigen::Vector3d> condyles;
  for (const auto& p : all)
    if (p.z() < z_min + 35) {
      condyles.push_back(p);
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  const Eigen::Vector3d mid = 0.5 * (lo + hi);
  std::array<std::vector<Eigen::Vector3d>, 2> side;
  for (const auto& p : condyles)
    if (p.y() > mid.y()) side[p.x() < mid.x() ? 0 : 1].push_back(p);
  Axis a;
  for (int k = 0; k < 2; ++k) a.spheres[k] = fit_sphere(side[k]);
  const Eigen::Vector3d c0 = a.spheres[0].head<3>(), c1 = a.spheres[1].head<3>();
  a.center = 0.5 * (c0 + c1);
  a.direction = (c1 - c0).normalized();
  return a;
}

// Nearest approach [mm] of the tibia and fibula (within the crop), rotated about the axis by
// each angle (a positive angle swings the tibia posteriorly), to the femur's surface; negative
// where a vertex would enter the femur.
std::vector<std::pair<int, double>> sweep_clearance(const Anatomy& a, const Axis& axis) {
  std::vector<Eigen::Vector3d> shin;
  for (const Surface* s : {a.tibia.get(), a.fibula.get()})
    for (const auto v : vertices(s->mesh)) {
      const Point& p = s->mesh.point(v);
      if (p.z() >= kZLow) shin.emplace_back(p.x(), p.y(), p.z());
    }
  std::vector<std::pair<int, double>> out;
  for (int deg = 0; deg <= 150; deg += 15) {
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(deg * M_PI / 180, axis.direction).toRotationMatrix();
    double nearest = 1e300;
    for (const auto& p : shin) {
      const Eigen::Vector3d q = axis.center + R * (p - axis.center);
      const Point pq(q.x(), q.y(), q.z());
      const double d = a.femur->distance(pq);
      nearest = std::min(nearest, a.femur->contains(pq) ? -d : d);
    }
    out.emplace_back(deg, nearest);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// The tet mesh after meshing: global vertices and tets with labels.

struct TetMesh {
  std::vector<std::array<double, 3>> xyz;  // [mm]
  std::vector<std::array<long, 4>> tets;
  std::vector<int> label;
};

// Vertices, and tets with their labels; vertices within 1e-3 mm of a cut plane are put on it.
TetMesh extract(const C3t3& c3t3) {
  TetMesh m;
  std::map<Tr::Vertex_handle, long> index;
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
    std::array<long, 4> t;
    for (int k = 0; k < 4; ++k) {
      const Tr::Vertex_handle v = c->vertex(k);
      auto [it, inserted] = index.emplace(v, static_cast<long>(m.xyz.size()));
      if (inserted) {
        const auto& p = v->point();
        double z = CGAL::to_double(p.z());
        for (const double cut : {kZLow, kZHigh})
          if (std::abs(z - cut) < 1e-3) z = cut;
        m.xyz.push_back({CGAL::to_double(p.x()), CGAL::to_double(p.y()), z});
      }
      t[k] = it->second;
    }
    m.tets.push_back(t);
    m.label.push_back(c3t3.subdomain_index(c));
  }
  return m;
}

using Face = std::array<long, 3>;

Face sorted(Face f) {
  std::sort(f.begin(), f.end());
  return f;
}

// Faces of tet t, each ordered so that its normal points out of the tet (for positive tets).
std::array<Face, 4> tet_faces(const std::array<long, 4>& t) {
  return {Face{t[1], t[2], t[3]}, Face{t[0], t[3], t[2]}, Face{t[0], t[1], t[3]},
          Face{t[0], t[2], t[1]}};
}

double volume6(const TetMesh& m, const std::array<long, 4>& t) {
  const auto& a = m.xyz[t[0]];
  double e[3][3];
  for (int k = 0; k < 3; ++k)
    for (int c = 0; c < 3; ++c) e[k][c] = m.xyz[t[k + 1]][c] - a[c];
  return e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
         e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
         e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
}

void orient_positive(TetMesh& m) {
  for (auto& t : m.tets)
    if (volume6(m, t) < 0) std::swap(t[2], t[3]);
}

// Boundary faces of the tets with label `l`, outward, in tet order.
std::vector<Face> boundary_faces(const TetMesh& m, int l) {
  std::map<Face, std::pair<Face, int>> count;  // sorted face -> (oriented face, count)
  for (size_t i = 0; i < m.tets.size(); ++i) {
    if (m.label[i] != l) continue;
    for (const Face& f : tet_faces(m.tets[i])) {
      auto [it, inserted] = count.emplace(sorted(f), std::make_pair(f, 0));
      ++it->second.second;
    }
  }
  std::vector<Face> out;
  for (size_t i = 0; i < m.tets.size(); ++i) {
    if (m.label[i] != l) continue;
    for (const Face& f : tet_faces(m.tets[i]))
      if (count.at(sorted(f)).second == 1) out.push_back(f);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// TetGen quality pass per label.

std::vector<std::vector<double>> read_table(const std::string& path, int skip_header_values) {
  std::ifstream in(path);
  if (!in) throw Fail(path + ": cannot open (did tetgen fail?)");
  std::vector<std::vector<double>> rows;
  std::string line;
  bool header = true;
  while (std::getline(in, line)) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    std::vector<double> row;
    double v;
    while (ls >> v) row.push_back(v);
    if (row.empty()) continue;
    if (header) {
      header = false;
      if (static_cast<int>(row.size()) < skip_header_values) throw Fail(path + ": bad header");
      continue;
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

// Replaces the tets of every label by TetGen's quality mesh of that label with the boundary kept.
TetMesh improve_with_tetgen(const TetMesh& in, const std::string& work) {
  TetMesh out;
  out.xyz = in.xyz;
  for (int l = 1; l <= kNumLabels; ++l) {
    // Local numbering of the label's vertices, in global order.
    std::vector<long> local(in.xyz.size(), -1), global;
    std::vector<std::array<long, 4>> tets;
    for (size_t i = 0; i < in.tets.size(); ++i) {
      if (in.label[i] != l) continue;
      tets.push_back(in.tets[i]);
      for (long v : in.tets[i]) local[v] = 0;
    }
    if (tets.empty()) throw Fail(std::string("no tets labelled ") + kLabelName[l]);
    for (size_t v = 0; v < local.size(); ++v)
      if (local[v] == 0) {
        local[v] = static_cast<long>(global.size());
        global.push_back(static_cast<long>(v));
      }
    const std::string base = work + "/" + kLabelName[l];
    {
      std::ofstream node(base + ".1.node");
      node << global.size() << " 3 0 0\n";
      node.precision(17);
      for (size_t k = 0; k < global.size(); ++k) {
        const auto& p = in.xyz[global[k]];
        node << k + 1 << " " << p[0] << " " << p[1] << " " << p[2] << "\n";
      }
      std::ofstream ele(base + ".1.ele");
      ele << tets.size() << " 4 0\n";
      for (size_t k = 0; k < tets.size(); ++k) {
        ele << k + 1;
        for (long v : tets[k]) ele << " " << local[v] + 1;
        ele << "\n";
      }
      const std::vector<Face> faces = boundary_faces(in, l);
      std::ofstream face(base + ".1.face");
      face << faces.size() << " 1\n";
      for (size_t k = 0; k < faces.size(); ++k) {
        face << k + 1;
        for (long v : faces[k]) face << " " << local[v] + 1;
        face << " 1\n";
      }
    }
    const std::string cmd = "tetgen -rYq1.5/15Q " + base + ".1";
    if (std::system(cmd.c_str()) != 0) throw Fail("'" + cmd + "' failed");
    const auto nodes = read_table(base + ".2.node", 4);
    const auto eles = read_table(base + ".2.ele", 3);
    if (nodes.size() < global.size()) throw Fail(base + ".2.node: lost input vertices");
    // TetGen keeps the input vertices first, in order; -Y adds none on the boundary.
    std::vector<long> to_global(nodes.size());
    for (size_t k = 0; k < nodes.size(); ++k) {
      if (k < global.size()) {
        to_global[k] = global[k];
        const auto& p = in.xyz[global[k]];
        for (int c = 0; c < 3; ++c)
          if (std::abs(nodes[k][c + 1] - p[c]) > 1e-9 * (1 + std::abs(p[c])))
            throw Fail(base + ".2.node: input vertex " + std::to_string(k + 1) + " moved");
      } else {
        to_global[k] = static_cast<long>(out.xyz.size());
        out.xyz.push_back({nodes[k][1], nodes[k][2], nodes[k][3]});
      }
    }
    for (const auto& e : eles) {
      std::array<long, 4> t;
      for (int c = 0; c < 4; ++c) t[c] = to_global[static_cast<size_t>(e[c + 1]) - 1];
      out.tets.push_back(t);
      out.label.push_back(l);
    }
  }
  orient_positive(out);
  return out;
}

// The six dihedral angles [degrees] of tet t.
std::array<double, 6> tet_dihedrals(const TetMesh& m, const std::array<long, 4>& t) {
  std::array<std::array<double, 3>, 4> n;  // outward face normals, face k opposite vertex k
  const std::array<Face, 4> faces = tet_faces(t);
  for (int k = 0; k < 4; ++k) {
    const auto& a = m.xyz[faces[k][0]];
    const auto& b = m.xyz[faces[k][1]];
    const auto& c = m.xyz[faces[k][2]];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[k] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    const double len = std::sqrt(n[k][0] * n[k][0] + n[k][1] * n[k][1] + n[k][2] * n[k][2]);
    for (double& x : n[k]) x /= len;
  }
  // The dihedral angle along the edge shared by faces j and k is pi minus the angle between
  // their outward normals.
  std::array<double, 6> out;
  int e = 0;
  for (int j = 0; j < 4; ++j)
    for (int k = j + 1; k < 4; ++k) {
      const double dot = n[j][0] * n[k][0] + n[j][1] * n[k][1] + n[j][2] * n[k][2];
      out[e++] = 180.0 - std::acos(std::clamp(dot, -1.0, 1.0)) * 180.0 / M_PI;
    }
  return out;
}

// Dihedral angles [degrees] of every tet of label l (6 per tet), sorted.
std::vector<double> dihedral_angles(const TetMesh& m, int l) {
  std::vector<double> out;
  for (size_t i = 0; i < m.tets.size(); ++i) {
    if (m.label[i] != l) continue;
    const std::array<double, 6> d = tet_dihedrals(m, m.tets[i]);
    out.insert(out.end(), d.begin(), d.end());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Splits at its centroid every tet whose four vertices all lie on the boundary of its region,
// where the four new tets keep a dihedral angle of at least kMinSplitDihedral. Material depth
// (the distance to the body's surface) is interpolated linearly from the nodes, so such a tet
// has zero depth throughout and contact cannot push anything out of it; its centroid is an
// interior point with positive depth. A flat tet (a sliver along the surface, whose interior is
// no deeper than its nodes) would split into slivers and is left as it is. Returns the number
// split and the number left.
constexpr double kMinSplitDihedral = 5.0;

std::pair<long, long> split_boundary_tets(TetMesh& m) {
  std::vector<std::vector<char>> on_boundary(kNumLabels + 1, std::vector<char>(m.xyz.size(), 0));
  for (int l = 1; l <= kNumLabels; ++l)
    for (const Face& f : boundary_faces(m, l))
      for (long v : f) on_boundary[l][v] = 1;
  const size_t n = m.tets.size();
  long split = 0, left = 0;
  for (size_t i = 0; i < n; ++i) {
    const std::array<long, 4> t = m.tets[i];
    bool all = true;
    for (long v : t) all = all && on_boundary[m.label[i]][v];
    if (!all) continue;
    std::array<double, 3> centroid = {0, 0, 0};
    for (long v : t)
      for (int c = 0; c < 3; ++c) centroid[c] += m.xyz[v][c] / 4;
    const long p = static_cast<long>(m.xyz.size());
    m.xyz.push_back(centroid);
    // Replacing vertex k by the centroid in turn gives four positive tets filling the old one.
    std::array<std::array<long, 4>, 4> sub;
    double worst = 180;
    for (int k = 0; k < 4; ++k) {
      sub[k] = t;
      sub[k][k] = p;
      for (double d : tet_dihedrals(m, sub[k])) worst = std::min(worst, d);
    }
    if (worst < kMinSplitDihedral) {
      m.xyz.pop_back();
      ++left;
      continue;
    }
    m.tets[i] = sub[0];
    for (int k = 1; k < 4; ++k) {
      m.tets.push_back(sub[k]);
      m.label.push_back(m.label[i]);
    }
    ++split;
  }
  return {split, left};
}

// ---------------------------------------------------------------------------------------------
// Surface groups and output.

struct Group {
  std::string name;
  std::vector<Face> faces;
};

std::vector<Group> surface_groups(const TetMesh& m, const Anatomy& anatomy) {
  // Two bones sharing a vertex would be glued there (one rigid body would drag the other).
  std::vector<int> bone_of(m.xyz.size(), 0);
  for (size_t i = 0; i < m.tets.size(); ++i) {
    if (m.label[i] == kSoftTissue) continue;
    for (long v : m.tets[i]) {
      if (bone_of[v] != 0 && bone_of[v] != m.label[i])
        throw Fail(std::string(kLabelName[bone_of[v]]) + " and " + kLabelName[m.label[i]] +
                   " share a vertex: refine near their gap");
      bone_of[v] = m.label[i];
    }
  }
  // Boundary faces of every label, keyed by sorted vertices.
  std::map<Face, std::vector<std::pair<int, Face>>> owners;
  for (int l = 1; l <= kNumLabels; ++l)
    for (const Face& f : boundary_faces(m, l)) owners[sorted(f)].emplace_back(l, f);
  std::vector<Group> groups = {{"femur_interface", {}},   {"tibia_interface", {}},
                               {"patella_interface", {}}, {"thigh_cut", {}},
                               {"shin_cut", {}},          {"femur_cut", {}},
                               {"tibia_cut", {}},         {"skin", {}},
                               {"joint_space", {}}};
  const auto group = [&](const std::string& name) -> Group& {
    for (Group& g : groups)
      if (g.name == name) return g;
    throw Fail("no group " + name);
  };
  for (const auto& [key, list] : owners) {
    if (list.size() == 2) {
      const int a = std::min(list[0].first, list[1].first),
                b = std::max(list[0].first, list[1].first);
      if (b != kSoftTissue)
        throw Fail(std::string(kLabelName[a]) + " and " + kLabelName[b] +
                   " share a face: refine near their gap");
      // The soft tissue's side of the interface, outward from the soft tissue.
      group(std::string(kLabelName[a]) + "_interface")
          .faces.push_back(list[0].first == kSoftTissue ? list[0].second : list[1].second);
      continue;
    }
    if (list.size() != 1) throw Fail("a face is shared by more than two labels");
    const auto [l, f] = list[0];
    double c[3] = {0, 0, 0};
    for (long v : f)
      for (int k = 0; k < 3; ++k) c[k] += m.xyz[v][k] / 3;
    bool on_cut = true;  // (cut vertices were snapped onto their plane)
    for (long v : f) on_cut = on_cut && (m.xyz[v][2] == kZLow || m.xyz[v][2] == kZHigh);
    if (on_cut) {
      const bool top = c[2] > 0.5 * (kZLow + kZHigh);
      if (l == kSoftTissue)
        group(top ? "thigh_cut" : "shin_cut").faces.push_back(f);
      else if (l == kFemur && top)
        group("femur_cut").faces.push_back(f);
      else if (l == kTibia && !top)
        group("tibia_cut").faces.push_back(f);
      else
        throw Fail(std::string(kLabelName[l]) + " has a face on the wrong cut plane");
      continue;
    }
    // Outside the label: beyond the skin (the faces approximate it within the facet distance), or
    // joint space deep inside it.
    const Point centroid(c[0], c[1], c[2]);
    if (anatomy.skin->distance(centroid) > 4 * anatomy.opt.facet_distance) {
      group("joint_space").faces.push_back(f);
    } else if (l == kSoftTissue) {
      group("skin").faces.push_back(f);
    } else {
      throw Fail(std::string(kLabelName[l]) + " reaches the skin");
    }
  }
  return groups;
}

double percentile(const std::vector<double>& sorted_values, double q) {
  const size_t k = static_cast<size_t>(q / 100.0 * static_cast<double>(sorted_values.size() - 1));
  return sorted_values[k];
}

// Writes MSH 4.1: one volume entity per label, one surface entity per group, nodes in blocks by
// the first label that uses them.
void write_msh(const TetMesh& m, const std::vector<Group>& groups, const std::string& path) {
  std::vector<int> node_label(m.xyz.size(), 0);
  for (size_t i = 0; i < m.tets.size(); ++i)
    for (long v : m.tets[i])
      if (node_label[v] == 0 || m.label[i] < node_label[v]) node_label[v] = m.label[i];
  std::vector<long> tag(m.xyz.size(), 0);  // 1-based, contiguous per block
  long next = 1;
  for (int l = 1; l <= kNumLabels; ++l)
    for (size_t v = 0; v < m.xyz.size(); ++v)
      if (node_label[v] == l) tag[v] = next++;
  for (size_t v = 0; v < m.xyz.size(); ++v)
    if (node_label[v] == 0) throw Fail("vertex " + std::to_string(v) + " belongs to no tet");

  std::ofstream out(path);
  char buf[160];
  out << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
  out << "$PhysicalNames\n" << kNumLabels + groups.size() << "\n";
  for (int l = 1; l <= kNumLabels; ++l) out << "3 " << l << " \"" << kLabelName[l] << "\"\n";
  for (size_t g = 0; g < groups.size(); ++g)
    out << "2 " << g + 1 << " \"" << groups[g].name << "\"\n";
  out << "$EndPhysicalNames\n";
  const auto box = [&](const auto& vertices_of) {
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    vertices_of([&](long v) {
      for (int c = 0; c < 3; ++c) {
        lo[c] = std::min(lo[c], m.xyz[v][c]);
        hi[c] = std::max(hi[c], m.xyz[v][c]);
      }
    });
    std::snprintf(buf, sizeof buf, "%.10g %.10g %.10g %.10g %.10g %.10g", lo[0], lo[1], lo[2],
                  hi[0], hi[1], hi[2]);
    return std::string(buf);
  };
  out << "$Entities\n0 0 " << groups.size() << " " << kNumLabels << "\n";
  for (size_t g = 0; g < groups.size(); ++g) {
    out << g + 1 << " " << box([&](auto visit) {
      for (const Face& f : groups[g].faces)
        for (long v : f) visit(v);
    }) << " 1 "
        << g + 1 << " 0\n";
  }
  for (int l = 1; l <= kNumLabels; ++l) {
    out << l << " " << box([&](auto visit) {
      for (size_t i = 0; i < m.tets.size(); ++i)
        if (m.label[i] == l)
          for (long v : m.tets[i]) visit(v);
    }) << " 1 "
        << l << " 0\n";
  }
  out << "$EndEntities\n";

  out << "$Nodes\n" << kNumLabels << " " << m.xyz.size() << " 1 " << m.xyz.size() << "\n";
  std::vector<std::vector<long>> block(kNumLabels + 1);
  for (size_t v = 0; v < m.xyz.size(); ++v) block[node_label[v]].push_back(static_cast<long>(v));
  for (int l = 1; l <= kNumLabels; ++l) {
    std::sort(block[l].begin(), block[l].end(), [&](long a, long b) { return tag[a] < tag[b]; });
    out << "3 " << l << " 0 " << block[l].size() << "\n";
    for (long v : block[l]) out << tag[v] << "\n";
    for (long v : block[l]) {
      std::snprintf(buf, sizeof buf, "%.10g %.10g %.10g\n", m.xyz[v][0], m.xyz[v][1], m.xyz[v][2]);
      out << buf;
    }
  }
  out << "$EndNodes\n";

  size_t num_tris = 0;
  for (const Group& g : groups) num_tris += g.faces.size();
  const size_t num_elements = m.tets.size() + num_tris;
  out << "$Elements\n"
      << kNumLabels + groups.size() << " " << num_elements << " 1 " << num_elements << "\n";
  long element = 1;
  for (int l = 1; l <= kNumLabels; ++l) {
    out << "3 " << l << " 4 " << std::count(m.label.begin(), m.label.end(), l) << "\n";
    for (size_t i = 0; i < m.tets.size(); ++i) {
      if (m.label[i] != l) continue;
      out << element++;
      for (long v : m.tets[i]) out << " " << tag[v];
      out << "\n";
    }
  }
  for (size_t g = 0; g < groups.size(); ++g) {
    out << "2 " << g + 1 << " 2 " << groups[g].faces.size() << "\n";
    for (const Face& f : groups[g].faces) {
      out << element++;
      for (long v : f) out << " " << tag[v];
      out << "\n";
    }
  }
  out << "$EndElements\n";
  if (!out) throw Fail(path + ": write failed");
}

// How smooth each bone's surface mesh is, as a Markdown table: the largest angle between the
// normals of two boundary triangles that share an edge (edges with both ends on a cut plane, the
// cut's rim among them, left out), the number of edges where it exceeds 60 and 90 degrees, and
// the largest distance of a boundary vertex off a cut plane from the bone's input surfaces (a
// fin of the bone reaching into the tissue stands off them; the tibia's are the tibia and the
// fibula, so the soft tissue between them made bone stands off by up to half the merge width).
std::string bone_surface_statistics(const TetMesh& m, const Anatomy& a) {
  const auto on_cut = [&](long v) { return m.xyz[v][2] == kZLow || m.xyz[v][2] == kZHigh; };
  const std::array<std::vector<const Surface*>, 3> inputs = {
      std::vector<const Surface*>{a.femur.get()},
      {a.tibia.get(), a.fibula.get()},
      {a.patella.get()}};
  std::ostringstream s;
  char buf[256];
  s << "bone surfaces: angle between the normals of boundary triangles sharing an edge (edges on "
       "the cut planes left out), distance of boundary vertices from the input surfaces\n\n"
       "| bone | largest angle [deg] | edges above 60 deg | edges above 90 deg | largest distance "
       "[mm] |\n|---|---|---|---|---|\n";
  for (int l = 1; l < kSoftTissue; ++l) {
    const std::vector<Face> faces = boundary_faces(m, l);
    std::vector<Eigen::Vector3d> normal;
    std::map<std::pair<long, long>, std::vector<size_t>> edge_faces;
    for (size_t i = 0; i < faces.size(); ++i) {
      const Face& f = faces[i];
      const auto x = [&](int k) { return Eigen::Vector3d(m.xyz[f[k]].data()); };
      normal.push_back((x(1) - x(0)).cross(x(2) - x(0)).normalized());
      for (int k = 0; k < 3; ++k) edge_faces[std::minmax(f[k], f[(k + 1) % 3])].push_back(i);
    }
    double largest = 0;
    int above_60 = 0, above_90 = 0;
    for (const auto& [edge, list] : edge_faces) {
      if (on_cut(edge.first) && on_cut(edge.second)) continue;
      const double angle =
          std::acos(std::clamp(normal[list[0]].dot(normal[list[1]]), -1.0, 1.0)) * 180 / M_PI;
      largest = std::max(largest, angle);
      above_60 += angle > 60;
      above_90 += angle > 90;
    }
    double off = 0;
    std::vector<char> seen(m.xyz.size(), 0);
    for (const Face& f : faces)
      for (long v : f) {
        if (on_cut(v) || seen[v]) continue;
        seen[v] = 1;
        const Point p(m.xyz[v][0], m.xyz[v][1], m.xyz[v][2]);
        double d = 1e300;
        for (const Surface* input : inputs[l - 1]) d = std::min(d, input->distance(p));
        off = std::max(off, d);
      }
    std::snprintf(buf, sizeof buf, "| %s | %.1f | %d | %d | %.2f |\n", kLabelName[l], largest,
                  above_60, above_90, off);
    s << buf;
  }
  return s.str();
}

// Mesh statistics as a Markdown table.
std::string statistics(const TetMesh& m, const std::vector<Group>& groups, const Options& o,
                       const Axis& axis, const std::vector<std::pair<int, double>>& clearance) {
  std::ostringstream s;
  char buf[256];
  size_t boundary = 0;
  for (int l = 1; l <= kNumLabels; ++l) boundary += boundary_faces(m, l).size();
  // Interfaces: every soft-tissue face on a bone must be a face of that bone's tets too (same
  // three vertices), which is what makes the two bodies coincide node for node.
  std::map<Face, int> bone_faces;
  for (int l = 1; l < kSoftTissue; ++l)
    for (const Face& f : boundary_faces(m, l)) bone_faces[sorted(f)] = l;
  std::snprintf(buf, sizeof buf,
                "knee_mesher --size %g --min-size %g --gap-factor %g (joint width %g mm, "
                "merge width %g mm, facet distance %g mm)\n\n",
                o.size, o.min_size, o.gap_factor, o.joint_width, o.merge_width, o.facet_distance);
  s << buf;
  s << "| region | nodes | tets | boundary triangles | min dihedral | 1st pct | 5th pct | median "
       "|\n"
       "|---|---|---|---|---|---|---|---|\n";
  for (int l = 1; l <= kNumLabels + 1; ++l) {
    const bool all = l == kNumLabels + 1;
    std::vector<char> used(m.xyz.size(), 0);
    size_t tets = 0;
    for (size_t i = 0; i < m.tets.size(); ++i)
      if (all || m.label[i] == l) {
        ++tets;
        for (long v : m.tets[i]) used[v] = 1;
      }
    std::vector<double> angles;
    size_t tris = 0;
    if (all) {
      for (int k = 1; k <= kNumLabels; ++k) {
        const auto a = dihedral_angles(m, k);
        angles.insert(angles.end(), a.begin(), a.end());
      }
      std::sort(angles.begin(), angles.end());
      tris = boundary;
    } else {
      angles = dihedral_angles(m, l);
      tris = boundary_faces(m, l).size();
    }
    // Nodes: a body's own copy of every vertex it uses (interface vertices count per body).
    size_t nodes = 0;
    if (all) {
      for (int k = 1; k <= kNumLabels; ++k) {
        std::vector<char> u(m.xyz.size(), 0);
        for (size_t i = 0; i < m.tets.size(); ++i)
          if (m.label[i] == k)
            for (long v : m.tets[i]) u[v] = 1;
        nodes += static_cast<size_t>(std::count(u.begin(), u.end(), 1));
      }
    } else {
      nodes = static_cast<size_t>(std::count(used.begin(), used.end(), 1));
    }
    std::snprintf(buf, sizeof buf, "| %s | %zu | %zu | %zu | %.1f | %.1f | %.1f | %.1f |\n",
                  all ? "all (separate bodies)" : kLabelName[l], nodes, tets, tris, angles.front(),
                  percentile(angles, 1), percentile(angles, 5), percentile(angles, 50));
    s << buf;
  }
  s << "\n| surface group | triangles | matched on the bone side |\n|---|---|---|\n";
  for (const Group& g : groups) {
    size_t matched = 0;
    const bool interface = g.name.ends_with("_interface");
    if (interface)
      for (const Face& f : g.faces) matched += bone_faces.count(sorted(f));
    s << "| " << g.name << " | " << g.faces.size() << " | "
      << (interface ? std::to_string(matched) : std::string("")) << " |\n";
  }
  for (int k = 0; k < 2; ++k) {
    const Eigen::Vector4d& q = axis.spheres[k];
    std::snprintf(buf, sizeof buf,
                  "\n%s condyle sphere: centre (%.2f, %.2f, %.2f) mm, radius %.2f mm",
                  k == 0 ? "lateral" : "medial", q(0), q(1), q(2), q(3));
    s << buf;
  }
  std::snprintf(buf, sizeof buf,
                "\n\nflexion axis: through (%.2f, %.2f, %.2f) mm, direction (%.4f, %.4f, %.4f)\n",
                axis.center.x(), axis.center.y(), axis.center.z(), axis.direction.x(),
                axis.direction.y(), axis.direction.z());
  s << buf << "\nnearest approach of tibia and fibula to the femur when rotated about it:\n\n"
    << "| angle [deg] |";
  for (const auto& [deg, d] : clearance) s << " " << deg << " |";
  s << "\n|---|";
  for (size_t k = 0; k < clearance.size(); ++k) s << "---|";
  s << "\n| distance [mm] |";
  for (const auto& [deg, d] : clearance) {
    std::snprintf(buf, sizeof buf, " %.2f |", d);
    s << buf;
  }
  s << "\n";
  return s.str();
}

Options parse(int argc, char** argv) {
  Options o;
  std::vector<std::string> pos;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw Fail(a + " needs a value");
      return argv[++i];
    };
    if (a == "--size")
      o.size = std::stod(value());
    else if (a == "--min-size")
      o.min_size = std::stod(value());
    else if (a == "--gap-factor")
      o.gap_factor = std::stod(value());
    else if (a == "--joint-width")
      o.joint_width = std::stod(value());
    else if (a == "--merge-width")
      o.merge_width = std::stod(value());
    else if (a == "--facet-distance")
      o.facet_distance = std::stod(value());
    else if (a == "--work")
      o.work = value();
    else if (a == "--stats")
      o.stats = value();
    else if (a.starts_with("--"))
      throw Fail("unknown option " + a);
    else
      pos.push_back(a);
  }
  if (pos.size() != 2)
    throw Fail(
        "usage: knee_mesher DATA_DIR OUT.msh [--size H] [--min-size H] [--gap-factor F] "
        "[--joint-width W] [--merge-width W] [--facet-distance D] [--work DIR] "
        "[--stats FILE.md]");
  o.data_dir = pos[0];
  o.out = pos[1];
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const auto start = std::chrono::steady_clock::now();
    Anatomy a;
    a.opt = parse(argc, argv);
    const Options& o = a.opt;
    std::filesystem::create_directories(o.work);
    const auto obj = [&](const char* f) { return o.data_dir + "/right_" + f + ".obj"; };
    a.femur = read_obj(obj("femur"), "femur");
    a.tibia = read_obj(obj("tibia"), "tibia");
    a.fibula = read_obj(obj("fibula"), "fibula");
    a.patella = read_obj(obj("patella"), "patella");
    a.skin = read_obj(obj("leg_skin"), "skin");

    // Bounding box: the skin's, cropped, with a margin.
    const CGAL::Bbox_3 skin_box = CGAL::Polygon_mesh_processing::bbox(a.skin->mesh);
    const K::Iso_cuboid_3 box(skin_box.xmin() - 5, skin_box.ymin() - 5, kZLow - 5,
                              skin_box.xmax() + 5, skin_box.ymax() + 5, kZHigh + 5);
    const std::function<int(const Point&)> label = [&a](const Point& p) { return a.label(p); };
    Domain domain(label, box, 1e-7);
    std::vector<std::vector<Point>> curves;
    add_cut_curves(*a.skin, kZLow, curves);
    add_cut_curves(*a.skin, kZHigh, curves);
    add_cut_curves(*a.femur, kZHigh, curves);
    add_cut_curves(*a.tibia, kZLow, curves);
    add_cut_curves(*a.fibula, kZLow, curves);
    const size_t num_cut_curves = curves.size();
    add_wall_curves(*a.femur, {a.tibia.get(), a.fibula.get()}, o.joint_width, curves);
    add_wall_curves(*a.femur, {a.patella.get()}, o.joint_width, curves);
    add_wall_curves(*a.tibia, {a.femur.get()}, o.joint_width, curves);
    add_wall_curves(*a.fibula, {a.femur.get()}, o.joint_width, curves);
    add_wall_curves(*a.patella, {a.femur.get()}, o.joint_width, curves);
    const size_t num_wall_curves = curves.size() - num_cut_curves;
    domain.add_features(curves.begin(), curves.end());

    // Edge lengths: the gap width times gap_factor near the joints, at most `size`. Surface
    // approximation: a facet bridging a gap of width g lies about g/2 from the surface, so a
    // bound of g/3 splits it until both bones have their own facets.
    const GapField sizing{&a, o.gap_factor, o.min_size, o.size};
    const GapField distance{&a, 1.0 / 3.0, 0.05, o.facet_distance};
    namespace p = CGAL::parameters;
    const Criteria criteria(p::edge_size = sizing, p::facet_angle = 25, p::facet_size = sizing,
                            p::facet_distance = distance, p::cell_radius_edge_ratio = 3,
                            p::cell_size = sizing);
    const C3t3 c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria, p::no_perturb(), p::no_exude());
    TetMesh mesh = extract(c3t3);
    orient_positive(mesh);
    std::cerr << "knee_mesher: CGAL: " << mesh.xyz.size() << " vertices, " << mesh.tets.size()
              << " tets\n";
    mesh = improve_with_tetgen(mesh, o.work);
    const auto [split, left] = split_boundary_tets(mesh);
    const std::vector<Group> groups = surface_groups(mesh, a);
    write_msh(mesh, groups, o.out);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const Axis axis = flexion_axis(*a.femur);
    const std::string stats =
        statistics(mesh, groups, o, axis, sweep_clearance(a, axis)) +
        "\ntets with all four vertices on their region's boundary: " + std::to_string(split) +
        " split at their centroid, " + std::to_string(left) + " left (they would split into " +
        "tets with a dihedral angle below 5 degrees)\n\nprotected curves: " +
        std::to_string(num_cut_curves) + " where the cut planes meet the skin and the bones, " +
        std::to_string(num_wall_curves) + " where the joint space meets a bone\n\n" +
        bone_surface_statistics(mesh, a);
    std::cerr << "knee_mesher: " << o.out << " in " << seconds << " s\n";
    std::cout << stats;
    if (!o.stats.empty()) std::ofstream(o.stats) << stats;
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "knee_mesher: error: " << e.what() << "\n";
    return 1;
  }
}
