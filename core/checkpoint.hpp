#pragma once
/// \file
/// Checkpoint files: the state of a run stopped part way, from which a later run continues to the
/// result, bit for bit, of a run that was not stopped (docs/restart.md, "Checkpoint and restart").
///
/// Format (version kCheckpointVersion), little-endian:
///   "PLYDEMCK" (8 bytes) | u32 version | u64 body length | u64 FNV-1a 64 of the body | body
/// and the body is the header (the run's kind and its settings, name = value strings) followed by
/// the payload, which the writers of the state fill in named sections (a u64 length and the name,
/// then what the section holds). Numbers are stored as their bits (doubles as IEEE 754 binary64),
/// arrays as a u64 count and their values; a model's particles and bonds field by field through
/// their declaration (Particles::for_each_field, Bonds::for_each_field): every field is written,
/// and a reader requires every field it declares, by name.
///
/// A file is written to FILE.tmp first and then renamed over FILE, so that a run killed while
/// writing leaves the previous checkpoint whole.
///
/// Errors (plydem::Error): "checkpoint F is not a plydem checkpoint", "checkpoint F is truncated
/// (...)", "checkpoint F is corrupt: checksum ... does not match ...", "checkpoint F has format
/// version N, this plydem reads M", "checkpoint F is for another run: ... there, ... here".

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/bond_failure.hpp"
#include "core/model.hpp"

namespace plydem {

/// The format version this build writes and reads. 2: the bonds' mixed-mode law fields
/// (mixed_mode_exponent, fracture_energy_ratio, peak_energy_ratio); a version 1 file lacks them
/// and is refused by its version. 3: each event's cracked site and its mode (failure at the
/// material point). 4: the cracked site's fracture angle, and which
/// of the events solver's changes since its last factorization were applied in one update. 5: the
/// sites' softening cracks, each event's tooth and the cracks' energy and area. 6: the bonds'
/// free offsets (cure stresses). 7: the events solver's preload (its state at the last critical
/// state, its energies and prescribed values). 8: the events solver's layer cracks' energy factors
/// (the coupled criterion). 9: without 8's flag that said whether those factors were kept (they
/// are kept across every event).
inline constexpr std::uint32_t kCheckpointVersion = 9;

/// FNV-1a 64 of `bytes`, continuing from `hash`.
std::uint64_t fnv1a64(std::string_view bytes, std::uint64_t hash = 0xcbf29ce484222325ull);

/// What a checkpoint belongs to: the kind of run (e.g. "strength/events") and the settings that
/// must be the same to continue it, as name = value strings, in a fixed order.
struct CheckpointHeader {
  std::string kind;
  std::vector<std::pair<std::string, std::string>> settings;

  void add(std::string name, std::string value) {
    settings.emplace_back(std::move(name), std::move(value));
  }
  /// FNV-1a 64 of the kind and every setting.
  std::uint64_t settings_hash() const;
};

/// Settings entries that fingerprint a model: one per field of its particles and bonds
/// ("model.bonds.tensile_strength" = FNV-1a 64 of the field's bits, in hex), and its size. What a
/// run is given to start from: a model built otherwise (another strategy, seed, packing, plydem
/// version) differs in some field, which a mismatch then names.
void add_model_fingerprint(CheckpointHeader& header, const Model& model,
                           const std::string& prefix = "model");

/// Formats a double for a settings entry so that different bits give different text.
std::string exact(double value);

/// Builds a payload.
class CheckpointWriter {
 public:
  /// Starts a named section (the reader's section() checks the name).
  void section(std::string_view name);
  void u8(std::uint8_t v);
  void u32(std::uint32_t v);
  void u64(std::uint64_t v);
  void i64(std::int64_t v);
  void f64(double v);
  void boolean(bool v) { u8(v ? 1 : 0); }
  void str(std::string_view s);
  void doubles(std::span<const double> v);
  void ints(std::span<const int> v);
  void array(const Eigen::ArrayXd& a) { doubles({a.data(), static_cast<std::size_t>(a.size())}); }
  void array(const Eigen::ArrayXi& a) { ints({a.data(), static_cast<std::size_t>(a.size())}); }
  /// Rows, then the three columns.
  void array(const Vector3Array& a);
  const std::string& bytes() const { return bytes_; }

 private:
  void raw(const void* data, std::size_t size);
  std::string bytes_;
};

/// Reads a payload; every read past its end, and every count that cannot fit in what is left,
/// throws plydem::Error ("checkpoint F is truncated ...").
class CheckpointReader {
 public:
  CheckpointReader(std::string bytes, std::string file);
  /// Reads a section's name; throws unless it is `name`.
  void section(std::string_view name);
  std::uint8_t u8();
  std::uint32_t u32();
  std::uint64_t u64();
  std::int64_t i64();
  double f64();
  bool boolean();
  std::string str();
  std::vector<double> doubles();
  std::vector<int> ints();
  /// Reads into `a`, which is resized to the stored count.
  void array(Eigen::ArrayXd& a);
  void array(Eigen::ArrayXi& a);
  void array(Vector3Array& a);
  /// Throws unless every byte was read.
  void finish() const;
  const std::string& file() const { return file_; }
  /// An error naming the file: "checkpoint F is corrupt: what".
  [[noreturn]] void corrupt(const std::string& what) const;

 private:
  void raw(void* data, std::size_t size, const char* what);
  std::uint64_t count(std::size_t element_size, const char* what);
  std::string bytes_;
  std::size_t at_ = 0;
  std::string file_;
};

/// Writes `header` and `payload` to `file` (FILE.tmp, then renamed). Throws plydem::Error when it
/// cannot write.
void write_checkpoint(const std::filesystem::path& file, const CheckpointHeader& header,
                      const CheckpointWriter& payload);

struct CheckpointFile {
  CheckpointHeader header;
  CheckpointReader payload;
};

/// Reads and checks a file: magic, version, length, checksum, header. Throws plydem::Error (see
/// the file comment).
CheckpointFile read_checkpoint(const std::filesystem::path& file);

/// Throws plydem::Error unless `stored` (from the file) and `here` name the same kind of run with
/// the same settings, naming the first that differs: "checkpoint F is for another run: seed is 1
/// there, 2 here".
void check_same_run(const CheckpointHeader& stored, const CheckpointHeader& here,
                    const std::string& file);

/// Throws plydem::Error ("checkpoint F is for another model: field mass of the particles differs
/// from this model's") unless every field of `saved` other than those named in `run_fields` (what
/// a run changes: displacements, damage, ...) equals the field of `here` to the bit.
void check_same_model(const Model& here, const Model& saved,
                      std::span<const std::string_view> run_fields, const std::string& file);

/// Checkpoint and restart of a run (the protocols' settings hold one): write the state to `file`
/// every `every` cycles or events (0 = never), continue from `restart` (empty = start afresh).
struct CheckpointOptions {
  std::filesystem::path file;
  long every = 0;
  std::filesystem::path restart;
  /// Throws plydem::Error: every without a file or a file without every, every < 0.
  void validate() const;
  bool writes() const { return every > 0; }
};

/// Every field of the model (through the field tables), its thickness and description.
void write_model(CheckpointWriter& out, const Model& model);
/// Reads what write_model wrote into `model` (every declared field must be there, by name).
void read_model(CheckpointReader& in, Model& model);
void write_particles(CheckpointWriter& out, const Particles& particles);
void read_particles(CheckpointReader& in, Particles& particles);
void write_bonds(CheckpointWriter& out, const Bonds& bonds);
void read_bonds(CheckpointReader& in, Bonds& bonds);
void write_breaks(CheckpointWriter& out, const std::vector<BondBreak>& breaks);
std::vector<BondBreak> read_breaks(CheckpointReader& in);

}  // namespace plydem
