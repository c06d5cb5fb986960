#include "core/checkpoint.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <bit>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <system_error>

#include "core/error.hpp"

namespace plydem {

static_assert(std::endian::native == std::endian::little,
              "checkpoint files are little-endian; this build writes the bits as they are");

namespace {

constexpr char kMagic[8] = {'P', 'L', 'Y', 'D', 'E', 'M', 'C', 'K'};
constexpr std::size_t kPrologue = sizeof kMagic + 4 + 8 + 8;  // magic, version, length, checksum

std::string hex(std::uint64_t v) {
  return fmt::format("{:016x}", v);
}

template <class Array>
std::uint64_t field_hash(const Array& a) {
  const std::string_view bytes(reinterpret_cast<const char*>(a.data()),
                               static_cast<std::size_t>(a.size()) * sizeof(*a.data()));
  return fnv1a64(bytes, fnv1a64(fmt::format("{}x{}", a.rows(), a.cols())));
}

template <class S>
void add_fields(CheckpointHeader& header, const S& s, const std::string& prefix) {
  S::for_each_field([&](const FieldInfo& info, auto member) {
    header.add(fmt::format("{}.{}", prefix, info.name), hex(field_hash(s.*member)));
  });
}

template <class S>
void write_fields(CheckpointWriter& out, const S& s) {
  std::uint32_t n = 0;
  S::for_each_field([&](const FieldInfo&, auto) { ++n; });
  out.u32(n);
  S::for_each_field([&](const FieldInfo& info, auto member) {
    using Array = FieldType<decltype(member)>;
    out.str(info.name);
    out.u8(static_cast<std::uint8_t>(field_kind<Array>()));
    out.array(s.*member);
  });
}

template <class S>
void read_fields(CheckpointReader& in, S& s, const char* what) {
  const std::uint32_t n = in.u32();
  std::vector<std::string> seen;
  for (std::uint32_t k = 0; k < n; ++k) {
    const std::string name = in.str();
    const auto kind = static_cast<FieldKind>(in.u8());
    bool known = false;
    S::for_each_field([&](const FieldInfo& info, auto member) {
      using Array = FieldType<decltype(member)>;
      if (known || name != info.name) return;
      known = true;
      if (kind != field_kind<Array>())
        in.corrupt(fmt::format("field {} of the {} has the wrong kind", name, what));
      in.array(s.*member);
    });
    if (!known)
      in.corrupt(fmt::format("the {} have a field '{}' this plydem does not know", what, name));
    for (const std::string& other : seen)
      if (other == name) in.corrupt(fmt::format("field {} of the {} is there twice", name, what));
    seen.push_back(name);
  }
  S::for_each_field([&](const FieldInfo& info, auto) {
    for (const std::string& name : seen)
      if (name == info.name) return;
    in.corrupt(fmt::format("field {} of the {} is missing", info.name, what));
  });
  try {
    s.check_sizes();
  } catch (const Error& e) {
    in.corrupt(fmt::format("the {}' fields differ in size: {}", what, e.what()));
  }
}

std::string header_bytes(const CheckpointHeader& header) {
  CheckpointWriter w;
  w.str(header.kind);
  w.u64(header.settings.size());
  for (const auto& [name, value] : header.settings) {
    w.str(name);
    w.str(value);
  }
  return w.bytes();
}

}  // namespace

std::uint64_t fnv1a64(std::string_view bytes, std::uint64_t hash) {
  for (const char c : bytes) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 0x100000001b3ull;
  }
  return hash;
}

std::uint64_t CheckpointHeader::settings_hash() const {
  return fnv1a64(header_bytes(*this));
}

void add_model_fingerprint(CheckpointHeader& header, const Model& model,
                           const std::string& prefix) {
  header.add(prefix + ".particles", fmt::format("{}", model.particles.size()));
  header.add(prefix + ".bonds", fmt::format("{}", model.bonds.size()));
  add_fields(header, model.particles, prefix + ".particles");
  add_fields(header, model.bonds, prefix + ".bonds");
  header.add(prefix + ".thickness", exact(model.thickness));
}

std::string exact(double value) {
  return fmt::format("{}", value);  // the shortest text that reads back to the same bits
}

// --- writer ---------------------------------------------------------------------------------

void CheckpointWriter::raw(const void* data, std::size_t size) {
  bytes_.append(static_cast<const char*>(data), size);
}
void CheckpointWriter::section(std::string_view name) {
  str(name);
}
void CheckpointWriter::u8(std::uint8_t v) {
  raw(&v, 1);
}
void CheckpointWriter::u32(std::uint32_t v) {
  raw(&v, 4);
}
void CheckpointWriter::u64(std::uint64_t v) {
  raw(&v, 8);
}
void CheckpointWriter::i64(std::int64_t v) {
  raw(&v, 8);
}
void CheckpointWriter::f64(double v) {
  raw(&v, 8);
}
void CheckpointWriter::str(std::string_view s) {
  u64(s.size());
  raw(s.data(), s.size());
}
void CheckpointWriter::doubles(std::span<const double> v) {
  u64(v.size());
  raw(v.data(), v.size() * sizeof(double));
}
void CheckpointWriter::ints(std::span<const int> v) {
  u64(v.size());
  for (const int x : v) i64(x);
}
void CheckpointWriter::array(const Vector3Array& a) {
  u64(static_cast<std::uint64_t>(a.rows()));
  raw(a.data(), static_cast<std::size_t>(a.size()) * sizeof(double));
}

// --- reader ---------------------------------------------------------------------------------

CheckpointReader::CheckpointReader(std::string bytes, std::string file)
    : bytes_(std::move(bytes)), file_(std::move(file)) {}

void CheckpointReader::corrupt(const std::string& what) const {
  throw Error(fmt::format("checkpoint {} is corrupt: {}", file_, what));
}

void CheckpointReader::raw(void* data, std::size_t size, const char* what) {
  if (size > bytes_.size() - at_)
    throw Error(fmt::format("checkpoint {} is truncated: {} bytes left where {} needs {}", file_,
                            bytes_.size() - at_, what, size));
  if (size > 0) std::memcpy(data, bytes_.data() + at_, size);
  at_ += size;
}

std::uint64_t CheckpointReader::count(std::size_t element_size, const char* what) {
  const std::uint64_t n = u64();
  if (n > (bytes_.size() - at_) / element_size)
    throw Error(
        fmt::format("checkpoint {} is truncated: {} of {} elements ({} bytes each) in {} "
                    "bytes left",
                    file_, what, n, element_size, bytes_.size() - at_));
  return n;
}

void CheckpointReader::section(std::string_view name) {
  const std::string found = str();
  if (found != name) corrupt(fmt::format("expected section '{}', found '{}'", name, found));
}
std::uint8_t CheckpointReader::u8() {
  std::uint8_t v;
  raw(&v, 1, "a byte");
  return v;
}
std::uint32_t CheckpointReader::u32() {
  std::uint32_t v;
  raw(&v, 4, "a u32");
  return v;
}
std::uint64_t CheckpointReader::u64() {
  std::uint64_t v;
  raw(&v, 8, "a u64");
  return v;
}
std::int64_t CheckpointReader::i64() {
  std::int64_t v;
  raw(&v, 8, "an i64");
  return v;
}
double CheckpointReader::f64() {
  double v;
  raw(&v, 8, "a double");
  return v;
}
bool CheckpointReader::boolean() {
  const std::uint8_t v = u8();
  if (v > 1) corrupt(fmt::format("a flag holds {}", v));
  return v == 1;
}
std::string CheckpointReader::str() {
  const std::uint64_t n = count(1, "a string");
  std::string s(n, '\0');
  raw(s.data(), n, "a string");
  return s;
}
std::vector<double> CheckpointReader::doubles() {
  const std::uint64_t n = count(sizeof(double), "an array");
  std::vector<double> v(n);
  raw(v.data(), n * sizeof(double), "an array");
  return v;
}
std::vector<int> CheckpointReader::ints() {
  const std::uint64_t n = count(8, "an integer array");
  std::vector<int> v(n);
  for (int& x : v) {
    const std::int64_t value = i64();
    if (value < std::numeric_limits<int>::min() || value > std::numeric_limits<int>::max())
      corrupt(fmt::format("an integer {} out of range", value));
    x = static_cast<int>(value);
  }
  return v;
}
void CheckpointReader::array(Eigen::ArrayXd& a) {
  const std::vector<double> v = doubles();
  a = Eigen::Map<const Eigen::ArrayXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}
void CheckpointReader::array(Eigen::ArrayXi& a) {
  const std::vector<int> v = ints();
  a = Eigen::Map<const Eigen::ArrayXi>(v.data(), static_cast<Eigen::Index>(v.size()));
}
void CheckpointReader::array(Vector3Array& a) {
  const std::uint64_t rows = count(3 * sizeof(double), "a vector array");
  a.resize(static_cast<Eigen::Index>(rows), 3);
  raw(a.data(), rows * 3 * sizeof(double), "a vector array");
}
void CheckpointReader::finish() const {
  if (at_ != bytes_.size())
    corrupt(fmt::format("{} bytes after the end of its state", bytes_.size() - at_));
}

// --- files ----------------------------------------------------------------------------------

void write_checkpoint(const std::filesystem::path& file, const CheckpointHeader& header,
                      const CheckpointWriter& payload) {
  const std::string body = header_bytes(header) + payload.bytes();
  const std::uint64_t length = body.size();
  const std::uint64_t checksum = fnv1a64(body);
  const std::uint32_t version = kCheckpointVersion;
  // A temporary of this process' own: under mpiexec every rank writes the same state to the same
  // file, and each rename replaces it whole.
  std::filesystem::path temporary = file;
  temporary += fmt::format(".{}.tmp", static_cast<long>(getpid()));
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    require(out.good(), fmt::format("cannot write checkpoint {}: cannot open {}", file.string(),
                                    temporary.string()));
    out.write(kMagic, sizeof kMagic);
    out.write(reinterpret_cast<const char*>(&version), 4);
    out.write(reinterpret_cast<const char*>(&length), 8);
    out.write(reinterpret_cast<const char*>(&checksum), 8);
    out.write(body.data(), static_cast<std::streamsize>(body.size()));
    out.flush();
    require(out.good(), fmt::format("cannot write checkpoint {}: writing {} failed (disk full?)",
                                    file.string(), temporary.string()));
  }
  std::error_code ec;
  std::filesystem::rename(temporary, file, ec);
  if (ec) {
    std::filesystem::remove(temporary, ec);
    throw Error(fmt::format("cannot write checkpoint {}: cannot rename {} over it", file.string(),
                            temporary.string()));
  }
}

CheckpointFile read_checkpoint(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::ifstream in(path, std::ios::binary);
  require(in.good(), fmt::format("cannot read checkpoint {}: no such file or not readable", file));
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.size() < sizeof kMagic || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    throw Error(
        fmt::format("checkpoint {} is not a plydem checkpoint (no PLYDEMCK at its start)", file));
  if (bytes.size() < kPrologue)
    throw Error(fmt::format("checkpoint {} is truncated: {} bytes, shorter than its prologue", file,
                            bytes.size()));
  std::uint32_t version;
  std::uint64_t length, checksum;
  std::memcpy(&version, bytes.data() + 8, 4);
  std::memcpy(&length, bytes.data() + 12, 8);
  std::memcpy(&checksum, bytes.data() + 20, 8);
  if (version != kCheckpointVersion)
    throw Error(fmt::format("checkpoint {} has format version {}, this plydem reads version {}",
                            file, version, kCheckpointVersion));
  if (bytes.size() - kPrologue < length)
    throw Error(fmt::format("checkpoint {} is truncated: {} bytes of its {} byte body", file,
                            bytes.size() - kPrologue, length));
  if (bytes.size() - kPrologue > length)
    throw Error(fmt::format("checkpoint {} is corrupt: {} bytes after its {} byte body", file,
                            bytes.size() - kPrologue - length, length));
  std::string body = bytes.substr(kPrologue);
  const std::uint64_t actual = fnv1a64(body);
  if (actual != checksum)
    throw Error(fmt::format("checkpoint {} is corrupt: checksum {} does not match the {} stored",
                            file, hex(actual), hex(checksum)));
  CheckpointReader reader(std::move(body), file);
  CheckpointHeader header;
  header.kind = reader.str();
  const std::uint64_t n = reader.u64();
  for (std::uint64_t k = 0; k < n; ++k) {
    std::string name = reader.str();
    std::string value = reader.str();
    header.add(std::move(name), std::move(value));
  }
  return {std::move(header), std::move(reader)};
}

void check_same_run(const CheckpointHeader& stored, const CheckpointHeader& here,
                    const std::string& file) {
  if (stored.kind != here.kind)
    throw Error(fmt::format("checkpoint {} is for another run: a {} run, this is {}", file,
                            stored.kind, here.kind));
  auto find = [](const CheckpointHeader& h, const std::string& name) -> const std::string* {
    for (const auto& [key, value] : h.settings)
      if (key == name) return &value;
    return nullptr;
  };
  for (const auto& [name, value] : here.settings) {
    const std::string* there = find(stored, name);
    if (!there)
      throw Error(fmt::format("checkpoint {} is for another run: it has no setting {} (here {})",
                              file, name, value));
    if (*there != value)
      throw Error(fmt::format("checkpoint {} is for another run: {} is {} there, {} here", file,
                              name, *there, value));
  }
  for (const auto& [name, value] : stored.settings)
    if (!find(here, name))
      throw Error(
          fmt::format("checkpoint {} is for another run: it has a setting {} = {} that "
                      "this run does not have",
                      file, name, value));
}

namespace {
template <class S>
void check_same_fields(const S& here, const S& saved, std::span<const std::string_view> run_fields,
                       const char* what, const std::string& file) {
  S::for_each_field([&](const FieldInfo& info, auto member) {
    for (std::string_view f : run_fields)
      if (f == info.name) return;
    const auto& a = here.*member;
    const auto& b = saved.*member;
    const bool same = a.rows() == b.rows() && a.cols() == b.cols() &&
                      std::memcmp(a.data(), b.data(),
                                  sizeof(*a.data()) * static_cast<std::size_t>(a.size())) == 0;
    if (!same)
      throw Error(
          fmt::format("checkpoint {} is for another model: field {} of the {} differs "
                      "from this model's",
                      file, info.name, what));
  });
}
}  // namespace

void check_same_model(const Model& here, const Model& saved,
                      std::span<const std::string_view> run_fields, const std::string& file) {
  require(
      here.particles.size() == saved.particles.size() && here.bonds.size() == saved.bonds.size(),
      fmt::format("checkpoint {} is for another model: {} particles and {} bonds there, {} "
                  "and {} here",
                  file, saved.particles.size(), saved.bonds.size(), here.particles.size(),
                  here.bonds.size()));
  check_same_fields(here.particles, saved.particles, run_fields, "particles", file);
  check_same_fields(here.bonds, saved.bonds, run_fields, "bonds", file);
}

void CheckpointOptions::validate() const {
  require(every >= 0, fmt::format("--checkpoint-every must be >= 0, got {}", every));
  require(every == 0 || !file.empty(),
          "--checkpoint-every needs --checkpoint FILE: the file to write the state to");
  require(file.empty() || every > 0,
          "--checkpoint FILE needs --checkpoint-every N: how often to write the state");
}

void write_particles(CheckpointWriter& out, const Particles& particles) {
  out.section("particles");
  write_fields(out, particles);
}
void read_particles(CheckpointReader& in, Particles& particles) {
  in.section("particles");
  read_fields(in, particles, "particles");
}
void write_bonds(CheckpointWriter& out, const Bonds& bonds) {
  out.section("bonds");
  write_fields(out, bonds);
}
void read_bonds(CheckpointReader& in, Bonds& bonds) {
  in.section("bonds");
  read_fields(in, bonds, "bonds");
}

void write_model(CheckpointWriter& out, const Model& model) {
  out.section("model");
  write_particles(out, model.particles);
  write_bonds(out, model.bonds);
  out.f64(model.thickness);
  out.str(model.description);
}

void read_model(CheckpointReader& in, Model& model) {
  in.section("model");
  read_particles(in, model.particles);
  read_bonds(in, model.bonds);
  model.thickness = in.f64();
  model.description = in.str();
}

void write_breaks(CheckpointWriter& out, const std::vector<BondBreak>& breaks) {
  out.section("breaks");
  out.u64(breaks.size());
  for (const BondBreak& b : breaks) {
    out.i64(b.bond);
    out.i64(static_cast<int>(b.mode));
    out.f64(b.at);
    out.f64(b.load);
    for (int c = 0; c < 3; ++c) out.f64(b.position(c));
  }
}

std::vector<BondBreak> read_breaks(CheckpointReader& in) {
  in.section("breaks");
  const std::uint64_t n = in.u64();
  std::vector<BondBreak> breaks;
  for (std::uint64_t k = 0; k < n; ++k) {
    BondBreak b;
    b.bond = static_cast<int>(in.i64());
    const std::int64_t mode = in.i64();
    if (mode != static_cast<int>(BondState::kBrokenTension) &&
        mode != static_cast<int>(BondState::kBrokenShear))
      in.corrupt(fmt::format("a break has mode {}", mode));
    b.mode = static_cast<BondState>(mode);
    b.at = in.f64();
    b.load = in.f64();
    for (int c = 0; c < 3; ++c) b.position(c) = in.f64();
    breaks.push_back(b);
  }
  return breaks;
}

}  // namespace plydem
