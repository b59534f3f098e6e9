// SPDX-License-Identifier: MIT
#include "io/rig_wire.h"

#include <cstdint>
#include <cstring>
#include <memory>
#include <type_traits>

#include "isokit/core/error.h"
#include "rig/clip_keys.h"

namespace isokit::skinning::io {

namespace {

class Writer {
 public:
  template <class T>
  void pod(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    out_.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  template <class T>
  void array(const T* data, std::size_t n) {
    pod(static_cast<std::uint64_t>(n));
    out_.append(reinterpret_cast<const char*>(data), n * sizeof(T));
  }
  void str(const std::string& s) { array(s.data(), s.size()); }
  template <class T>
  void vec(const std::vector<T>& v) {
    array(v.data(), v.size());
  }
  void affine(const Affine& a) { out_.append(reinterpret_cast<const char*>(a.data()), 16 * sizeof(double)); }
  std::string take() { return std::move(out_); }

 private:
  std::string out_;
};

class Reader {
 public:
  Reader(const std::string& bytes, const std::string& source) : bytes_(bytes), source_(source) {}
  template <class T>
  T pod() {
    T v;
    take(&v, sizeof v);
    return v;
  }
  std::size_t count(std::size_t element_size) {
    const auto n = pod<std::uint64_t>();
    check(element_size == 0 || n <= (bytes_.size() - pos_) / element_size);
    return static_cast<std::size_t>(n);
  }
  std::string str() {
    std::string s(count(1), '\0');
    take(s.data(), s.size());
    return s;
  }
  template <class T>
  std::vector<T> vec() {
    std::vector<T> v(count(sizeof(T)));
    take(v.data(), v.size() * sizeof(T));
    return v;
  }
  Affine affine() {
    Affine a;
    take(a.data(), 16 * sizeof(double));
    return a;
  }
  void check(bool ok) const {
    require(ok, source_, "the importer's child process sent a truncated rig",
            "report it as a bug; set LoadOptions::isolate_importer = false to read in this process");
  }
  bool done() const { return pos_ == bytes_.size(); }

 private:
  void take(void* dst, std::size_t n) {
    check(n <= bytes_.size() - pos_);
    if (n > 0) std::memcpy(dst, bytes_.data() + pos_, n);
    pos_ += n;
  }
  const std::string& bytes_;
  const std::string& source_;
  std::size_t pos_{0};
};

template <class M>
void write_matrix(Writer& w, const M& m) {
  w.pod(static_cast<std::int64_t>(m.rows()));
  w.array(m.data(), static_cast<std::size_t>(m.size()));
}

template <class M>
void read_matrix(Reader& r, M& m) {
  const auto rows = r.pod<std::int64_t>();
  r.check(rows >= 0);
  const auto values = r.vec<typename M::Scalar>();
  r.check(values.size() == static_cast<std::size_t>(rows) * 3);
  m.resize(static_cast<Eigen::Index>(rows), 3);
  if (!values.empty()) std::memcpy(m.data(), values.data(), values.size() * sizeof(typename M::Scalar));
}

template <class Value>
void write_track(Writer& w, const KeyTrack<Value>& t) {
  w.vec(t.time);
  w.array(t.value.data(), t.value.size());
}

template <class Value>
KeyTrack<Value> read_track(Reader& r) {
  KeyTrack<Value> t;
  t.time = r.vec<double>();
  t.value = r.vec<Value>();
  r.check(t.value.size() == t.time.size());
  return t;
}

template <class V, int N>
V read_fixed(Reader& r) {
  const std::vector<double> v = r.vec<double>();
  r.check(v.size() == N);
  return Eigen::Map<const V>(v.data());
}

void write_keys(Writer& w, const ClipKeys& k) {
  w.pod(k.ticks_per_second);
  w.pod(k.last_seconds);
  w.pod(static_cast<std::uint64_t>(k.nodes.size()));
  for (const ClipKeys::Node& n : k.nodes) {
    w.pod(n.parent);
    w.pod(static_cast<std::uint8_t>(n.relevant));
    w.pod(static_cast<std::uint8_t>(n.keyed));
    w.affine(n.local);
    w.array(n.rest.t.data(), 3);
    w.array(n.rest.r.coeffs().data(), 4);
    w.array(n.rest.s.data(), 3);
    write_track(w, n.translation);
    write_track(w, n.rotation);
    write_track(w, n.scale);
  }
  w.vec(k.joint_node);
  w.vec(k.joint_parent);
}

ClipKeys read_keys(Reader& r) {
  ClipKeys k;
  k.ticks_per_second = r.pod<double>();
  k.last_seconds = r.pod<double>();
  k.nodes.resize(r.count(sizeof(int) + 2 + 16 * sizeof(double)));
  for (ClipKeys::Node& n : k.nodes) {
    n.parent = r.pod<int>();
    n.relevant = r.pod<std::uint8_t>() != 0;
    n.keyed = r.pod<std::uint8_t>() != 0;
    n.local = r.affine();
    n.rest.t = read_fixed<Eigen::Vector3d, 3>(r);
    n.rest.r.coeffs() = read_fixed<Eigen::Vector4d, 4>(r);
    n.rest.s = read_fixed<Eigen::Vector3d, 3>(r);
    n.translation = read_track<Eigen::Vector3d>(r);
    n.rotation = read_track<Eigen::Quaterniond>(r);
    n.scale = read_track<Eigen::Vector3d>(r);
  }
  k.joint_node = r.vec<int>();
  k.joint_parent = r.vec<int>();
  return k;
}

}  // namespace

std::string encode_rig(const Rig& rig, const LoadReport& report) {
  Writer w;
  w.str(rig.name);
  write_matrix(w, rig.rest);
  write_matrix(w, rig.triangles);
  w.vec(rig.weights.offsets);
  w.vec(rig.weights.joints);
  w.vec(rig.weights.weights);
  w.pod(static_cast<std::uint64_t>(rig.joints.size()));
  for (const Joint& j : rig.joints) {
    w.str(j.name);
    w.pod(j.parent);
    w.affine(j.rest_local);
    w.affine(j.inverse_bind);
    w.str(j.file_name);
  }
  w.pod(static_cast<std::uint64_t>(rig.clips.size()));
  for (const Clip& c : rig.clips) {
    w.str(c.name);
    w.pod(c.fps);
    w.pod(static_cast<std::uint8_t>(c.keys != nullptr));
    if (c.keys != nullptr) write_keys(w, *c.keys);
    w.pod(static_cast<std::uint64_t>(c.local.size()));
    for (const auto& frame : c.local) {
      w.pod(static_cast<std::uint64_t>(frame.size()));
      for (const Affine& a : frame) w.affine(a);
    }
  }
  w.vec(rig.output.to_welded);
  write_matrix(w, rig.output.triangles);
  w.vec(rig.output.primitive_offsets);
  w.vec(rig.relax_mask);
  w.str(report.format);
  w.str(report.mask_source);
  for (int v : {report.meshes, report.file_vertices, report.welded_vertices, report.max_influences,
                report.dropped_triangles, int(report.weights_from_file)})
    w.pod(v);
  w.pod(static_cast<std::uint64_t>(report.warnings.size()));
  for (const auto& s : report.warnings) w.str(s);
  return w.take();
}

void decode_rig(const std::string& bytes, const std::string& source, Rig& rig, LoadReport& report) {
  Reader r(bytes, source);
  rig = Rig{};
  rig.name = r.str();
  read_matrix(r, rig.rest);
  read_matrix(r, rig.triangles);
  rig.weights.offsets = r.vec<int>();
  rig.weights.joints = r.vec<int>();
  rig.weights.weights = r.vec<float>();
  const std::size_t nj = r.count(1);
  for (std::size_t i = 0; i < nj; ++i) {
    Joint j;
    j.name = r.str();
    j.parent = r.pod<int>();
    j.rest_local = r.affine();
    j.inverse_bind = r.affine();
    j.file_name = r.str();
    rig.joints.push_back(std::move(j));
  }
  const std::size_t nc = r.count(1);
  for (std::size_t i = 0; i < nc; ++i) {
    Clip c;
    c.name = r.str();
    c.fps = r.pod<double>();
    if (r.pod<std::uint8_t>() != 0) c.keys = std::make_shared<const ClipKeys>(read_keys(r));
    c.local.resize(r.count(1));
    for (auto& frame : c.local) {
      frame.resize(r.count(16 * sizeof(double)));
      for (Affine& a : frame) a = r.affine();
    }
    rig.clips.push_back(std::move(c));
  }
  rig.output.to_welded = r.vec<int>();
  read_matrix(r, rig.output.triangles);
  rig.output.primitive_offsets = r.vec<int>();
  rig.relax_mask = r.vec<float>();
  report = LoadReport{};
  report.format = r.str();
  report.mask_source = r.str();
  for (int* v : {&report.meshes, &report.file_vertices, &report.welded_vertices, &report.max_influences,
                 &report.dropped_triangles})
    *v = r.pod<int>();
  report.weights_from_file = r.pod<int>() != 0;
  report.warnings.resize(r.count(1));
  for (auto& s : report.warnings) s = r.str();
  r.check(r.done());
}

}  // namespace isokit::skinning::io
