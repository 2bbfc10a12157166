// Generates the big scenes the benchmarks and tests measure on: real
// interiors have 10^4 to 10^6 faces, most of them small, many of them
// pieces of one flat surface, and the shipped scenes have a few hundred.
//
//   scenegen boxes N OUT.obj [SEED]
//     A 10 x 10 x 4 room (y up) with a ceiling light and a grid of N boxes
//     of random heights in three colours: 7 + 5 N faces (box bottoms, which
//     rest on the floor, are left out).
//   scenegen tessellate IN.obj K OUT.obj [--tri]
//     IN with every face cut K x K (a quad by its bilinear grid, a triangle
//     into K^2 triangles, a larger polygon fanned into triangles first),
//     each cell split into two triangles with --tri: the geometry an
//     exporter produces for the same surfaces. Materials, objects and the
//     camera comment are kept; the MTL file is copied beside OUT.
//
// Writes by hand, not through the program's own loader: the output must
// be what another tool would write, and this is a stand-alone tool.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct V3 {
  double x, y, z;
};
V3 Lerp(V3 a, V3 b, double t) {
  return {a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t, a.z + (b.z - a.z) * t};
}

[[noreturn]] void Die(const std::string& what) {
  std::cerr << "scenegen: " << what << "\n";
  std::exit(2);
}

std::string Dir(const std::string& path) {
  size_t s = path.rfind('/');
  return s == std::string::npos ? "." : path.substr(0, s);
}

std::string Base(const std::string& path) {
  size_t s = path.rfind('/');
  return s == std::string::npos ? path : path.substr(s + 1);
}

std::string Stem(const std::string& path) {
  std::string b = Base(path);
  size_t d = b.rfind('.');
  return d == std::string::npos ? b : b.substr(0, d);
}

// Collects vertices and faces and writes them as OBJ; %.9g keeps a
// double's cut points exact enough that coplanar pieces stay coplanar.
class Obj {
 public:
  explicit Obj(const std::string& path) : out_(path) {
    if (!out_) Die("cannot write " + path);
  }
  void Line(const std::string& s) { out_ << s << "\n"; }
  int Vertex(V3 p) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "v %.9g %.9g %.9g\n", p.x, p.y, p.z);
    out_ << buf;
    return ++verts_;
  }
  void Face(const std::vector<int>& ids) {
    out_ << "f";
    for (int i : ids) out_ << " " << i;
    out_ << "\n";
    ++faces_;
  }
  // A convex polygon by its corners, counter-clockwise from the front.
  void Polygon(const std::vector<V3>& pts) {
    std::vector<int> ids;
    for (const V3& p : pts) ids.push_back(Vertex(p));
    Face(ids);
  }
  long faces() const { return faces_; }

 private:
  std::ofstream out_;
  int verts_ = 0;
  long faces_ = 0;
};

// An axis-aligned box from lo to hi without its bottom face: its five
// faces, outward and counter-clockwise.
void Box(Obj* obj, V3 lo, V3 hi) {
  double x0 = lo.x, y0 = lo.y, z0 = lo.z, x1 = hi.x, y1 = hi.y, z1 = hi.z;
  obj->Polygon({{x0, y1, z0}, {x0, y1, z1}, {x1, y1, z1}, {x1, y1, z0}});  // top
  obj->Polygon({{x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}});  // +z
  obj->Polygon({{x1, y0, z0}, {x0, y0, z0}, {x0, y1, z0}, {x1, y1, z0}});  // -z
  obj->Polygon({{x1, y0, z1}, {x1, y0, z0}, {x1, y1, z0}, {x1, y1, z1}});  // +x
  obj->Polygon({{x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1}, {x0, y1, z0}});  // -x
}

int Boxes(int n, const std::string& out, unsigned seed) {
  if (n < 0) Die("boxes: N must be >= 0");
  const double W = 10, H = 4, D = 10;
  std::string mtl = Stem(out) + ".mtl";
  {
    std::ofstream m(Dir(out) + "/" + mtl);
    if (!m) Die("cannot write " + Dir(out) + "/" + mtl);
    m << "newmtl floor\nKd 0.55 0.5 0.45\n"
         "newmtl wall\nKd 0.75 0.75 0.72\n"
         "newmtl ceiling\nKd 0.8 0.8 0.8\n"
         "newmtl light\nKd 0 0 0\nKe 40 40 36\n"
         "newmtl red\nKd 0.7 0.15 0.1\n"
         "newmtl green\nKd 0.15 0.6 0.2\n"
         "newmtl blue\nKd 0.15 0.25 0.7\n";
  }
  Obj obj(out);
  obj.Line("# A 10 x 10 x 4 room with a ceiling light and a grid of " + std::to_string(n) +
           " boxes (bench/scenegen.cpp).");
  obj.Line("# camera 9.5 3.2 9.5 3 0.5 3 70");
  obj.Line("mtllib " + mtl);
  obj.Line("o room");
  obj.Line("usemtl floor");
  obj.Polygon({{0, 0, D}, {W, 0, D}, {W, 0, 0}, {0, 0, 0}});
  obj.Line("usemtl ceiling");
  obj.Polygon({{0, H, 0}, {W, H, 0}, {W, H, D}, {0, H, D}});
  obj.Line("usemtl wall");
  obj.Polygon({{0, 0, 0}, {W, 0, 0}, {W, H, 0}, {0, H, 0}});
  obj.Polygon({{W, 0, D}, {0, 0, D}, {0, H, D}, {W, H, D}});
  obj.Polygon({{0, 0, D}, {0, 0, 0}, {0, H, 0}, {0, H, D}});
  obj.Polygon({{W, 0, 0}, {W, 0, D}, {W, H, D}, {W, H, 0}});
  obj.Line("o light");
  obj.Line("usemtl light");
  const double l0 = 4, l1 = 6, ly = H - 0.001;
  obj.Polygon({{l0, ly, l0}, {l1, ly, l0}, {l1, ly, l1}, {l0, ly, l1}});  // facing down
  // A square grid of cells over the floor, one box in each, filled row by row.
  int side = int(std::ceil(std::sqrt(double(n))));
  double cell = (W - 1.0) / std::max(side, 1);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> height(0.05, 1.5), fill(0.4, 0.8);
  const char* colours[3] = {"red", "green", "blue"};
  obj.Line("o boxes");
  for (int i = 0; i < n; ++i) {
    int gx = i % side, gz = i / side;
    double s = cell * fill(rng), h = height(rng);
    double cx = 0.5 + (gx + 0.5) * cell, cz = 0.5 + (gz + 0.5) * cell;
    obj.Line(std::string("usemtl ") + colours[i % 3]);
    Box(&obj, {cx - s / 2, 0, cz - s / 2}, {cx + s / 2, h, cz + s / 2});
  }
  std::cerr << "scenegen: " << out << ": " << obj.faces() << " faces\n";
  return 0;
}

std::vector<std::string> Words(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> w;
  for (std::string s; in >> s;) w.push_back(s);
  return w;
}

// Cuts one convex polygon into pieces k x k, as two triangles per cell
// when `tri`.
void Cut(Obj* obj, const std::vector<V3>& p, int k, bool tri) {
  auto emit = [&](V3 a, V3 b, V3 c, V3 d) {  // a cell, counter-clockwise
    if (tri) {
      obj->Polygon({a, b, c});
      obj->Polygon({a, c, d});
    } else {
      obj->Polygon({a, b, c, d});
    }
  };
  if (p.size() == 4) {
    auto at = [&](int i, int j) {  // bilinear grid point i along p0->p1, j along p0->p3
      double u = double(i) / k, v = double(j) / k;
      return Lerp(Lerp(p[0], p[1], u), Lerp(p[3], p[2], u), v);
    };
    for (int j = 0; j < k; ++j)
      for (int i = 0; i < k; ++i) emit(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
    return;
  }
  for (size_t t = 1; t + 1 < p.size(); ++t) {  // a fan of triangles, each cut k^2
    V3 a = p[0], b = p[t], c = p[t + 1];
    auto at = [&](int i, int j) {  // i along a->b, j along a->c, i + j <= k
      double u = double(i) / k, v = double(j) / k;
      return V3{a.x + (b.x - a.x) * u + (c.x - a.x) * v, a.y + (b.y - a.y) * u + (c.y - a.y) * v,
                a.z + (b.z - a.z) * u + (c.z - a.z) * v};
    };
    for (int j = 0; j < k; ++j)
      for (int i = 0; i + j < k; ++i) {
        obj->Polygon({at(i, j), at(i + 1, j), at(i, j + 1)});
        if (i + j + 1 < k) obj->Polygon({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
      }
  }
}

int Tessellate(const std::string& in_path, int k, const std::string& out, bool tri) {
  if (k < 1) Die("tessellate: K must be >= 1");
  std::ifstream in(in_path);
  if (!in) Die("cannot open " + in_path);
  Obj obj(out);
  std::vector<V3> verts;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> w = Words(line);
    if (w.empty()) continue;
    if (w[0] == "v" && w.size() >= 4) {
      verts.push_back({std::atof(w[1].c_str()), std::atof(w[2].c_str()), std::atof(w[3].c_str())});
    } else if (w[0] == "f") {
      std::vector<V3> poly;
      for (size_t i = 1; i < w.size(); ++i) {
        long id = std::atol(w[i].c_str());  // "7/1/2" reads as 7
        if (id < 0) id += long(verts.size()) + 1;
        if (id < 1 || id > long(verts.size())) Die(in_path + ": bad vertex in: " + line);
        poly.push_back(verts[id - 1]);
      }
      Cut(&obj, poly, k, tri);
    } else if (w[0] == "mtllib" && w.size() == 2) {
      std::ifstream src(Dir(in_path) + "/" + w[1]);
      std::string copy = Stem(out) + ".mtl";
      std::ofstream dst(Dir(out) + "/" + copy);
      if (!src || !dst) Die("cannot copy " + w[1]);
      dst << src.rdbuf();
      obj.Line("mtllib " + copy);
    } else if (w[0] == "usemtl" || w[0] == "o" || (w[0] == "#" && w.size() > 1 && w[1] == "camera")) {
      obj.Line(line);
    }
  }
  std::cerr << "scenegen: " << out << ": " << obj.faces() << " faces\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> a(argv + 1, argv + argc);
  if (a.size() >= 3 && a[0] == "boxes")
    return Boxes(std::atoi(a[1].c_str()), a[2], a.size() > 3 ? unsigned(std::atol(a[3].c_str())) : 1u);
  if ((a.size() == 4 || (a.size() == 5 && a[4] == "--tri")) && a[0] == "tessellate")
    return Tessellate(a[1], std::atoi(a[2].c_str()), a[3], a.size() == 5);
  std::cerr << "usage: scenegen boxes N OUT.obj [SEED]\n"
               "       scenegen tessellate IN.obj K OUT.obj [--tri]\n";
  return 2;
}
