// CGAL's exact Nef-polyhedron Minkowski sum, a benchmark peer of cspace (never a dependency).
//
// Usage: cgal_minkowski A.off B.off OUT.off
// A: a closed polyhedron; B: a closed convex polyhedron (already -R). Coordinates are read as
// doubles (exact in the kernel: every double is a rational). Prints one line:
//   seconds <build s> volume <exact numerator>/<exact denominator>
// and writes the sum's boundary, triangulated, with coordinates rounded to double, to OUT.off.
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Nef_polyhedron_3.h>
#include <CGAL/Polyhedron_3.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/convert_nef_polyhedron_to_polygon_mesh.h>
#include <CGAL/minkowski_sum_3.h>

#include <chrono>
#include <fstream>
#include <iomanip>
#include <iostream>

typedef CGAL::Exact_predicates_exact_constructions_kernel Kernel;
typedef Kernel::Point_3 Point;
typedef CGAL::Polyhedron_3<Kernel> Polyhedron;
typedef CGAL::Nef_polyhedron_3<Kernel> Nef;
typedef CGAL::Surface_mesh<Point> Mesh;

static Polyhedron read_off(const char* path) {
  std::ifstream in(path);
  Polyhedron p;
  if (!(in >> p) || !p.is_closed()) {
    std::cerr << path << ": not a closed polyhedron in OFF\n";
    std::exit(2);
  }
  return p;
}

int main(int argc, char** argv) {
  if (argc != 4) {
    std::cerr << "usage: cgal_minkowski A.off B.off OUT.off\n";
    return 2;
  }
  Polyhedron pa = read_off(argv[1]), pb = read_off(argv[2]);
  auto t0 = std::chrono::steady_clock::now();
  Nef a(pa), b(pb);
  Nef sum = CGAL::minkowski_sum_3(a, b);
  Mesh out;
  CGAL::convert_nef_polyhedron_to_polygon_mesh(sum, out, true);
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // Exact volume: signed tetrahedra against the origin over the outward triangles.
  Kernel::FT six = 0;
  Point o(0, 0, 0);
  for (auto f : out.faces()) {
    std::vector<Point> v;
    for (auto h : CGAL::halfedges_around_face(out.halfedge(f), out)) v.push_back(out.point(out.target(h)));
    six += CGAL::determinant(v[0] - o, v[1] - o, v[2] - o);
  }
  auto vol = CGAL::exact(six / 6);
  std::cout << "seconds " << seconds << " volume " << vol  // prints n/d
            << "\n";
  std::ofstream off(argv[3]);
  off << std::setprecision(17) << "OFF\n" << out.number_of_vertices() << " " << out.number_of_faces() << " 0\n";
  std::map<Mesh::Vertex_index, std::size_t> id;
  std::size_t k = 0;
  for (auto v : out.vertices()) {
    id[v] = k++;
    const Point& p = out.point(v);
    off << CGAL::to_double(p.x()) << " " << CGAL::to_double(p.y()) << " " << CGAL::to_double(p.z()) << "\n";
  }
  for (auto f : out.faces()) {
    off << "3";
    for (auto h : CGAL::halfedges_around_face(out.halfedge(f), out)) off << " " << id[out.target(h)];
    off << "\n";
  }
  return 0;
}
