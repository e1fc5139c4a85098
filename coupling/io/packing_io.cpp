// Packing files: NAME.csv (the interchange format), NAME.json (metadata), NAME.vtp (for ParaView).
#include "coupling/io/packing_io.h"

#include "coupling/io/atomic_file.h"

#include <algorithm>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string_view>

#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkIdTypeArray.h>
#include <vtkTypeInt64Array.h>
#include <vtkXMLPolyDataWriter.h>

namespace btr {
namespace fs = std::filesystem;

namespace {

// A packing with rigid clusters has a seventh column, cluster (0 = a free grain); one without any
// keeps the six-column form, byte for byte as before clusters existed.
constexpr const char* kHeader = "id,x,y,z,radius,species";
constexpr const char* kClusterHeader = "id,x,y,z,radius,species,cluster";
constexpr const char* kColumns[] = {"id", "x", "y", "z", "radius", "species", "cluster"};

[[noreturn]] void csv_error(const std::string& file, std::int64_t line, const std::string& what) {
  throw std::runtime_error(file + ":" + std::to_string(line) + ": " + what);
}

std::string excerpt(std::string_view s) {
  constexpr std::size_t kMax = 40;
  std::string out(s.substr(0, kMax));
  if (s.size() > kMax) out += "...";
  return "'" + out + "'";
}

double parse_double(std::string_view field, const std::string& file, std::int64_t line, int col) {
  std::string text(field);
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  double v = std::strtod(begin, &end);
  // errno == ERANGE on underflow is fine: %.17g of a subnormal reads back exactly.
  if (text.empty() || end != begin + text.size() || !std::isfinite(v))
    csv_error(file, line, std::string("column '") + kColumns[col] + "': expected a finite number, got " +
                              excerpt(field));
  return v;
}

std::int64_t parse_int(std::string_view field, const std::string& file, std::int64_t line, int col) {
  std::string text(field);
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  long long v = std::strtoll(begin, &end, 10);
  if (text.empty() || end != begin + text.size() || errno == ERANGE)
    csv_error(file, line, std::string("column '") + kColumns[col] + "': expected an integer, got " +
                              excerpt(field));
  return v;
}

Grains read_csv(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open packing file: " + std::strerror(errno));
  Grains grains;
  std::string text;
  std::int64_t line_no = 0;
  std::int64_t blank_line = 0;  // first blank line seen; only trailing blank lines are allowed
  int columns = 6;
  while (std::getline(in, text)) {
    ++line_no;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    if (line_no == 1) {
      if (text == kClusterHeader) columns = 7;
      else if (text != kHeader)
        csv_error(path, 1, std::string("expected the header '") + kHeader + "' or '" + kClusterHeader + "', got " +
                               excerpt(text));
      continue;
    }
    if (text.empty()) {
      if (blank_line == 0) blank_line = line_no;
      continue;
    }
    if (blank_line != 0) csv_error(path, blank_line, "blank line inside the data");

    std::string_view fields[7];
    std::string_view rest(text);
    int n = 0;
    const std::string header = columns == 7 ? kClusterHeader : kHeader;
    while (true) {
      std::size_t comma = rest.find(',');
      if (n == columns)
        csv_error(path, line_no, "expected " + std::to_string(columns) + " columns (" + header + "), got more");
      fields[n++] = rest.substr(0, comma);
      if (comma == std::string_view::npos) break;
      rest.remove_prefix(comma + 1);
    }
    if (n != columns)
      csv_error(path, line_no,
                "expected " + std::to_string(columns) + " columns (" + header + "), got " + std::to_string(n));

    const std::int64_t expected_id = static_cast<std::int64_t>(grains.size()) + 1;
    std::int64_t id = parse_int(fields[0], path, line_no, 0);
    if (id != expected_id)
      csv_error(path, line_no, "column 'id': expected " + std::to_string(expected_id) +
                                   " (ids are 1..N in order), got " + std::to_string(id));
    Grain g;
    g.x = Vec3(parse_double(fields[1], path, line_no, 1), parse_double(fields[2], path, line_no, 2),
               parse_double(fields[3], path, line_no, 3));
    g.r = parse_double(fields[4], path, line_no, 4);
    if (!(g.r > 0.0))
      csv_error(path, line_no, "column 'radius': expected a positive number, got " + excerpt(fields[4]));
    std::int64_t species = parse_int(fields[5], path, line_no, 5);
    if (species < 1 || species > 1000000)
      csv_error(path, line_no, "column 'species': expected an integer >= 1, got " + excerpt(fields[5]));
    g.species = static_cast<int>(species);
    if (columns == 7) {
      const std::int64_t cluster = parse_int(fields[6], path, line_no, 6);
      if (cluster < 0 || cluster > 2000000000)
        csv_error(path, line_no, "column 'cluster': expected an integer >= 0 (0 = a free grain), got " +
                                     excerpt(fields[6]));
      g.cluster = static_cast<std::int32_t>(cluster);
    }
    grains.push_back(g);
  }
  if (in.bad()) throw std::runtime_error(path + ": read error: " + std::strerror(errno));
  if (line_no == 0) csv_error(path, 1, std::string("expected the header '") + kHeader + "', the file is empty");
  return grains;
}

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

// Returns the digest of the bytes written (computed as they are written, not read back).
FileDigest write_csv(const TempFile& file, const Grains& grains) {
  const std::string name = file.final_path().string();
  std::unique_ptr<std::FILE, FileCloser> f(std::fopen(file.temp().c_str(), "wb"));
  if (!f) throw std::runtime_error(name + ": cannot create " + file.temp().string() + ": " + std::strerror(errno));
  const bool clusters = std::any_of(grains.begin(), grains.end(), [](const Grain& g) { return g.cluster != 0; });
  std::string buffer = std::string(clusters ? kClusterHeader : kHeader) + "\n";
  char row[256];
  FileDigest digest;
  auto flush = [&] {
    if (std::fwrite(buffer.data(), 1, buffer.size(), f.get()) != buffer.size())
      throw std::runtime_error(name + ": write error: " + std::strerror(errno));
    digest.add(buffer.data(), buffer.size());
    buffer.clear();
  };
  for (std::size_t i = 0; i < grains.size(); ++i) {
    const Grain& g = grains[i];
    int n = clusters ? std::snprintf(row, sizeof row, "%zu,%.17g,%.17g,%.17g,%.17g,%d,%d\n", i + 1, g.x.x(),
                                     g.x.y(), g.x.z(), g.r, g.species, static_cast<int>(g.cluster))
                     : std::snprintf(row, sizeof row, "%zu,%.17g,%.17g,%.17g,%.17g,%d\n", i + 1, g.x.x(), g.x.y(),
                                     g.x.z(), g.r, g.species);
    buffer.append(row, static_cast<std::size_t>(n));
    if (buffer.size() > (1u << 20)) flush();
  }
  flush();
  if (std::fclose(f.release()) != 0) throw std::runtime_error(name + ": write error: " + std::strerror(errno));
  return digest;
}

void write_json(const TempFile& file, const nlohmann::json& meta) {
  const std::string name = file.final_path().string();
  std::ofstream out(file.temp(), std::ios::binary);
  if (!out) throw std::runtime_error(name + ": cannot create " + file.temp().string() + ": " + std::strerror(errno));
  out << (meta.is_null() ? nlohmann::json::object() : meta).dump(2) << '\n';
  out.close();
  if (!out) throw std::runtime_error(name + ": write error");
}

void write_vtp(const TempFile& file, const Grains& grains, const std::vector<PointData>& extra) {
  const vtkIdType n = static_cast<vtkIdType>(grains.size());
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  vtkNew<vtkDoubleArray> radius;
  radius->SetName("radius");
  radius->SetNumberOfValues(n);
  vtkNew<vtkTypeInt64Array> id;
  id->SetName("id");
  id->SetNumberOfValues(n);
  vtkNew<vtkIntArray> species;
  species->SetName("species");
  species->SetNumberOfValues(n);
  vtkNew<vtkIntArray> cluster;  // colour by cluster in ParaView (0 = a free grain)
  cluster->SetName("cluster");
  cluster->SetNumberOfValues(n);
  vtkNew<vtkIdTypeArray> offsets, connectivity;
  offsets->SetNumberOfValues(n + 1);
  connectivity->SetNumberOfValues(n);
  for (vtkIdType i = 0; i < n; ++i) {
    const Grain& g = grains[static_cast<std::size_t>(i)];
    points->SetPoint(i, g.x.x(), g.x.y(), g.x.z());
    radius->SetValue(i, g.r);
    id->SetValue(i, i + 1);
    species->SetValue(i, g.species);
    cluster->SetValue(i, g.cluster);
    offsets->SetValue(i, i);
    connectivity->SetValue(i, i);
  }
  offsets->SetValue(n, n);
  vtkNew<vtkCellArray> verts;  // one vertex cell per grain, so ParaView draws the points as they are
  verts->SetData(offsets, connectivity);

  vtkNew<vtkPolyData> poly;
  poly->SetPoints(points);
  poly->SetVerts(verts);
  poly->GetPointData()->AddArray(radius);
  poly->GetPointData()->AddArray(id);
  poly->GetPointData()->AddArray(species);
  if (std::any_of(grains.begin(), grains.end(), [](const Grain& g) { return g.cluster != 0; }))
    poly->GetPointData()->AddArray(cluster);
  poly->GetPointData()->SetActiveScalars("radius");
  for (const PointData& pd : extra) {
    vtkNew<vtkDoubleArray> a;
    a->SetName(pd.name.c_str());
    a->SetNumberOfValues(n);
    for (vtkIdType i = 0; i < n; ++i) a->SetValue(i, pd.values[static_cast<std::size_t>(i)]);
    poly->GetPointData()->AddArray(a);
  }

  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->SetFileName(file.temp().c_str());
  writer->SetInputData(poly);
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();  // raw binary
  writer->SetCompressorTypeToLZ4();
  writer->SetHeaderTypeToUInt64();
  if (writer->Write() != 1 || writer->GetErrorCode() != 0)
    throw std::runtime_error(file.final_path().string() + ": VTK could not write " + file.temp().string());
}

}  // namespace

namespace {

// The record of the files written with a packing's JSON (key "files"): what a reader checks the CSV against.
nlohmann::json file_record(const FileDigest& d) { return {{"bytes", d.bytes}, {"crc32", d.crc32}}; }

// A CSV whose JSON records other bytes belongs to another write (or was cut short): refused.
void check_against_record(const fs::path& csv, const fs::path& json_path, const nlohmann::json& meta) {
  if (!meta.contains("files") || !meta["files"].is_object() || !meta["files"].contains("csv")) return;
  const nlohmann::json& rec = meta["files"]["csv"];
  if (!rec.is_object() || !rec.contains("bytes") || !rec.contains("crc32") || !rec["bytes"].is_number_unsigned() ||
      !rec["crc32"].is_number_unsigned())
    throw std::runtime_error(json_path.string() + ": files.csv: expected {\"bytes\": N, \"crc32\": N}");
  const FileDigest d = digest_file(csv);
  if (d.bytes != rec["bytes"].get<std::uint64_t>() || d.crc32 != rec["crc32"].get<std::uint32_t>())
    throw std::runtime_error(csv.string() + ": does not match the record in " + json_path.string() + " (" +
                             std::to_string(d.bytes) + " bytes, CRC-32 " + std::to_string(d.crc32) + "; recorded " +
                             rec["bytes"].dump() + " bytes, CRC-32 " + rec["crc32"].dump() +
                             "): the two were not written together (an interrupted write, or one file replaced); "
                             "write the packing again, or remove the JSON's \"files\" entry if the CSV was edited "
                             "on purpose");
}

}  // namespace

Packing read_packing(const std::string& csv_path) {
  Packing packing;
  packing.grains = read_csv(csv_path);
  fs::path json_path = fs::path(csv_path).replace_extension(".json");
  packing.meta = nlohmann::json::object();
  if (fs::exists(json_path)) {
    std::ifstream in(json_path, std::ios::binary);
    if (!in) throw std::runtime_error(json_path.string() + ": cannot open: " + std::strerror(errno));
    try {
      packing.meta = nlohmann::json::parse(in);
    } catch (const nlohmann::json::parse_error& e) {
      throw std::runtime_error(json_path.string() + ": not valid JSON: " + e.what());
    }
    if (!packing.meta.is_object())
      throw std::runtime_error(json_path.string() + ": expected a JSON object at the top level");
    check_against_record(csv_path, json_path, packing.meta);
    packing.meta.erase("files");  // it describes these files only; a packing written from this one gets its own
  }
  return packing;
}

void write_packing(const std::string& dir, const std::string& name, const Packing& packing,
                   const std::vector<PointData>& extra) {
  if (name.empty() || name.find('/') != std::string::npos)
    throw std::runtime_error("packing name '" + name + "': expected a file name without '/'");
  for (const PointData& pd : extra) {
    if (pd.values.size() != packing.grains.size())
      throw std::runtime_error("point data '" + pd.name + "': expected " + std::to_string(packing.grains.size()) +
                               " values (one per grain), got " + std::to_string(pd.values.size()));
    if (pd.name.empty() || pd.name == "radius" || pd.name == "id" || pd.name == "species" ||
        pd.name == "cluster")
      throw std::runtime_error("point data '" + pd.name + "': expected a non-empty name other than radius, id, species, cluster");
  }
  std::error_code ec;
  fs::create_directories(dir.empty() ? fs::path(".") : fs::path(dir), ec);
  if (ec) throw std::runtime_error(dir + ": cannot create the output folder: " + ec.message());

  const fs::path base = (dir.empty() ? fs::path(".") : fs::path(dir)) / name;
  // All three are written under temporary names first; a failure there leaves the previous packing of
  // that name untouched. The JSON records the CSV's and VTP's sizes and CRC-32 and is renamed last, after
  // the previous JSON was removed: a crash part-way leaves no JSON, or one that matches its CSV, never an
  // old record beside new grains (readers check the record).
  TempFile csv(fs::path(base.string() + ".csv"));
  TempFile vtp(fs::path(base.string() + ".vtp"));
  TempFile json(fs::path(base.string() + ".json"));
  const FileDigest csv_digest = write_csv(csv, packing.grains);
  write_vtp(vtp, packing.grains, extra);  // VTK writes the file itself: its digest is read back
  nlohmann::json meta = packing.meta.is_object() ? packing.meta : nlohmann::json::object();
  meta["files"] = {{"csv", file_record(csv_digest)}, {"vtp", file_record(digest_file(vtp.temp()))}};
  write_json(json, meta);
  fs::remove(json.final_path(), ec);
  if (ec) throw std::runtime_error(json.final_path().string() + ": cannot replace it: " + ec.message());
  csv.commit();
  vtp.commit();
  json.commit();
}

void write_packing_meta(const std::string& dir, const std::string& name, const nlohmann::json& meta) {
  const fs::path base = (dir.empty() ? fs::path(".") : fs::path(dir)) / name;
  TempFile json(fs::path(base.string() + ".json"));
  nlohmann::json out = meta.is_object() ? meta : nlohmann::json::object();
  // The files did not change: their record is the one of the JSON written with them, whatever meta says.
  out.erase("files");
  {
    std::ifstream in(json.final_path(), std::ios::binary);
    const nlohmann::json old = in ? nlohmann::json::parse(in, nullptr, false) : nlohmann::json();
    if (old.is_object() && old.contains("files")) out["files"] = old["files"];
  }
  write_json(json, out);
  json.commit();
}

}  // namespace btr
