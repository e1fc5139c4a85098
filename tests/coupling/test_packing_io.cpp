// Packing files: exact CSV round trip, clear errors, temporary-then-rename writes, a VTP VTK can read.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkObject.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkXMLPolyDataReader.h>

#include "coupling/io/atomic_file.h"
#include "coupling/io/packing_io.h"

namespace btr {
namespace {
namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& tag) {
  fs::path d = fs::temp_directory_path() / ("btr_packing_io_" + tag + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void spit(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Grains whose coordinates need all 17 digits, plus awkward values (negative zero, tiny, huge).
Packing awkward_packing(std::size_t n) {
  std::mt19937_64 rng(42);
  auto u = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  Packing p;
  for (std::size_t i = 0; i < n; ++i) {
    Grain g;
    g.x = Vec3(u() * 0.1 - 0.05, (u() - 0.5) * 1e-7, u() / 3.0);
    g.r = 1e-3 * (0.5 + u());
    g.species = 1 + static_cast<int>(rng() % 3);
    p.grains.push_back(g);
  }
  p.grains[0].x = Vec3(-0.0, 1e-300, 1.0 / 3.0);
  p.grains[1].x = Vec3(std::nextafter(0.1, 1.0), -1e300, 5e-324);
  p.grains[2].r = std::numeric_limits<double>::min();
  p.meta = {{"scene_name", "awkward"}, {"seed", 18446744073709551615ull}, {"x", 0.1 + 0.2}};
  return p;
}

TEST(PackingIO, RoundTripIsExactToTheBit) {
  const fs::path dir = fresh_dir("roundtrip") / "nested" / "out";  // created by write_packing
  const Packing p = awkward_packing(500);
  write_packing(dir.string(), "pack", p);
  const Packing q = read_packing((dir / "pack.csv").string());
  ASSERT_EQ(q.grains.size(), p.grains.size());
  for (std::size_t i = 0; i < p.grains.size(); ++i) {
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(same_bits(p.grains[i].x[k], q.grains[i].x[k])) << i << " " << k;
    EXPECT_TRUE(same_bits(p.grains[i].r, q.grains[i].r)) << i;
    EXPECT_EQ(p.grains[i].species, q.grains[i].species) << i;
  }
  EXPECT_EQ(q.meta, p.meta);
  EXPECT_TRUE(same_bits(q.meta["x"].get<double>(), 0.1 + 0.2));
  // writing what was read gives the same bytes
  write_packing(dir.string(), "again", q);
  EXPECT_EQ(slurp(dir / "pack.csv"), slurp(dir / "again.csv"));
  // the CSV is what the format says: header, then id 1..N
  std::istringstream csv(slurp(dir / "pack.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "id,x,y,z,radius,species");
  std::getline(csv, line);
  EXPECT_EQ(line.substr(0, 5), "1,-0,");
  fs::remove_all(fresh_dir("roundtrip"));
}

TEST(PackingIO, OnlyTheThreeFilesAreLeft) {
  const fs::path dir = fresh_dir("files");
  write_packing(dir.string(), "p", awkward_packing(20));
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"p.csv", "p.json", "p.vtp"}));
  fs::remove_all(dir);
}

TEST(PackingIO, AFailedWriteKeepsThePreviousPackingAndLeavesNoTemporaryFile) {
  const fs::path dir = fresh_dir("fail");
  const Packing old = awkward_packing(30);
  write_packing(dir.string(), "p", old);
  const std::string csv = slurp(dir / "p.csv"), json = slurp(dir / "p.json"), vtp = slurp(dir / "p.vtp");

  // Metadata that cannot be written as JSON (a string that is not UTF-8): the CSV and VTP temporary files
  // are written first, then the JSON fails, before anything is renamed.
  Packing bad = awkward_packing(40);
  bad.meta["note"] = std::string("\xff\xfe");
  EXPECT_ANY_THROW(write_packing(dir.string(), "p", bad));
  EXPECT_EQ(slurp(dir / "p.csv"), csv);
  EXPECT_EQ(slurp(dir / "p.json"), json);
  EXPECT_EQ(slurp(dir / "p.vtp"), vtp);
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    EXPECT_EQ(name.find(".tmp"), std::string::npos) << name;
  }

  // Point data of the wrong length is refused before anything is written.
  EXPECT_THROW(write_packing(dir.string(), "p", awkward_packing(40), {{"bad", std::vector<double>(39)}}),
               std::runtime_error);
  EXPECT_EQ(slurp(dir / "p.csv"), csv);
  fs::remove_all(dir);
}

TEST(PackingIO, VtpHasPointsVerticesAndArrays) {
  const fs::path dir = fresh_dir("vtp");
  const Packing p = awkward_packing(123);
  std::vector<double> extra(p.grains.size());
  for (std::size_t i = 0; i < extra.size(); ++i) extra[i] = 0.5 * double(i);
  write_packing(dir.string(), "p", p, {{"displacement", extra}});

  vtkNew<vtkXMLPolyDataReader> reader;
  reader->SetFileName((dir / "p.vtp").c_str());
  reader->Update();
  vtkPolyData* poly = reader->GetOutput();
  ASSERT_EQ(poly->GetNumberOfPoints(), 123);
  EXPECT_EQ(poly->GetNumberOfVerts(), 123);  // ParaView shows the points without a glyph
  vtkPointData* pd = poly->GetPointData();
  vtkDataArray* radius = pd->GetArray("radius");
  vtkDataArray* id = pd->GetArray("id");
  vtkDataArray* species = pd->GetArray("species");
  vtkDataArray* disp = pd->GetArray("displacement");
  ASSERT_TRUE(radius && id && species && disp);
  for (vtkIdType i = 0; i < 123; ++i) {
    const Grain& g = p.grains[static_cast<std::size_t>(i)];
    double x[3];
    poly->GetPoint(i, x);
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(same_bits(x[k], g.x[k])) << i;
    EXPECT_TRUE(same_bits(radius->GetTuple1(i), g.r)) << i;
    EXPECT_EQ(id->GetTuple1(i), double(i + 1));
    EXPECT_EQ(species->GetTuple1(i), double(g.species));
    EXPECT_EQ(disp->GetTuple1(i), 0.5 * double(i));
  }
  fs::remove_all(dir);
}

// ------------------------------------------------------------ bad CSV

std::string read_error(const fs::path& file) {
  try {
    read_packing(file.string());
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(PackingIO, BadCsvErrorsNameFileLineAndWhatWasExpected) {
  const fs::path dir = fresh_dir("bad");
  fs::create_directories(dir);
  const std::string head = "id,x,y,z,radius,species\n";
  const std::string good = "1,0,0,0.001,0.001,1\n";
  struct Case {
    std::string text, needle;
    int line;
  } cases[] = {
      {"id,x,y,z,r,species\n" + good, "expected the header 'id,x,y,z,radius,species'", 1},
      {head + good + "3,0,0,0.003,0.001,1\n", "column 'id': expected 2", 3},
      {head + good + "2,0,0,abc,0.001,1\n", "column 'z': expected a finite number, got 'abc'", 3},
      {head + good + "2,0,0,0.1,0.001\n", "expected 6 columns", 3},
      {head + good + "2,0,0,0.1,0.001,1,7\n", "expected 6 columns", 3},
      {head + "1,0,0,0.001,-0.001,1\n", "column 'radius': expected a positive number", 2},
      {head + "1,0,0,0.001,0.001,0\n", "column 'species': expected an integer >= 1", 2},
      {head + "1,0,0,0.001,0.001,1.5\n", "column 'species': expected an integer", 2},
      {head + "1,0,0,nan,0.001,1\n", "column 'z': expected a finite number", 2},
      {head + good + "\n2,0,0,0.1,0.001,1\n", "blank line", 3},
      {"", "the file is empty", 1},
  };
  int k = 0;
  for (const Case& c : cases) {
    const fs::path f = dir / ("bad" + std::to_string(k++) + ".csv");
    spit(f, c.text);
    const std::string msg = read_error(f);
    EXPECT_NE(msg.find(f.string() + ":" + std::to_string(c.line) + ":"), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.needle), std::string::npos) << msg;
  }
  // trailing blank lines and Windows line ends are fine
  spit(dir / "ok.csv", "id,x,y,z,radius,species\r\n1,0,0,0.001,0.001,2\r\n\n\n");
  const Packing ok = read_packing((dir / "ok.csv").string());
  ASSERT_EQ(ok.grains.size(), 1u);
  EXPECT_EQ(ok.grains[0].species, 2);
  EXPECT_TRUE(ok.meta.is_object() && ok.meta.empty());
  // a broken NAME.json beside it is named in the error
  spit(dir / "ok.json", "{\"seed\": ");
  const std::string msg = read_error(dir / "ok.csv");
  EXPECT_NE(msg.find((dir / "ok.json").string()), std::string::npos) << msg;
  EXPECT_NE(read_error(dir / "missing.csv").find("missing.csv"), std::string::npos);
  fs::remove_all(dir);
}

// A packing with clusters gains the cluster column (bit-exact round trip, VTP array); its absence
// keeps the six-column form; a bad cluster value is named.
TEST(PackingIO, ClusterColumnRoundTripsAndIsOptional) {
  const fs::path dir = fresh_dir("clusters");
  Packing p = awkward_packing(50);
  write_packing(dir.string(), "free", p);
  EXPECT_EQ(slurp(dir / "free.csv").substr(0, 24), "id,x,y,z,radius,species\n");
  for (std::size_t i = 0; i < p.grains.size(); ++i) p.grains[i].cluster = static_cast<std::int32_t>(i / 3);
  write_packing(dir.string(), "clustered", p);
  std::istringstream csv(slurp(dir / "clustered.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "id,x,y,z,radius,species,cluster");
  std::getline(csv, line);
  EXPECT_EQ(line.substr(line.size() - 2), ",0");
  const Packing q = read_packing((dir / "clustered.csv").string());
  ASSERT_EQ(q.grains.size(), p.grains.size());
  for (std::size_t i = 0; i < p.grains.size(); ++i) {
    EXPECT_EQ(q.grains[i].cluster, p.grains[i].cluster) << i;
    EXPECT_TRUE(same_bits(q.grains[i].x.z(), p.grains[i].x.z())) << i;
  }
  vtkNew<vtkXMLPolyDataReader> reader;
  reader->SetFileName((dir / "clustered.vtp").c_str());
  reader->Update();
  vtkDataArray* cl = reader->GetOutput()->GetPointData()->GetArray("cluster");
  ASSERT_NE(cl, nullptr);
  EXPECT_EQ(cl->GetTuple1(49), 16.0);
  spit(dir / "bad.csv", "id,x,y,z,radius,species,cluster\n1,0,0,0.001,0.001,1,-2\n");
  const std::string msg = read_error(dir / "bad.csv");
  EXPECT_NE(msg.find("bad.csv:2: column 'cluster': expected an integer >= 0"), std::string::npos) << msg;
  fs::remove_all(dir);
}

TEST(AtomicFile, TwoWritersOfOneFileGetTheirOwnTemporaryFiles) {
  const fs::path dir = fresh_dir("temp");
  fs::create_directories(dir);
  {
    TempFile a(dir / "x.csv"), b(dir / "x.csv");
    EXPECT_NE(a.temp(), b.temp());
    EXPECT_TRUE(fs::exists(a.temp()) && fs::exists(b.temp()));
    EXPECT_EQ(a.temp().parent_path(), dir);
    spit(a.temp(), "a\n");
    a.commit();
    EXPECT_EQ(slurp(dir / "x.csv"), "a\n");
    // A committed file has the permissions a new file gets, not mkstemp's owner-only 0600.
    EXPECT_NE(fs::status(dir / "x.csv").permissions() & fs::perms::others_read, fs::perms::none);
  }
  // b was never committed: its temporary file is gone, a's content stays.
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  EXPECT_EQ(names, std::vector<std::string>{"x.csv"});
  fs::remove_all(dir);
}

TEST(PackingIO, TheJsonRecordsTheFilesAndARecordThatDoesNotMatchIsRefused) {
  const fs::path dir = fresh_dir("record");
  write_packing(dir.string(), "p", awkward_packing(30));
  std::ifstream in(dir / "p.json");
  const nlohmann::json meta = nlohmann::json::parse(in);
  const FileDigest csv = digest_file(dir / "p.csv"), vtp = digest_file(dir / "p.vtp");
  EXPECT_EQ(meta["files"]["csv"]["bytes"].get<std::uint64_t>(), fs::file_size(dir / "p.csv"));
  EXPECT_EQ(meta["files"]["csv"]["crc32"].get<std::uint32_t>(), csv.crc32);
  EXPECT_EQ(meta["files"]["vtp"]["crc32"].get<std::uint32_t>(), vtp.crc32);
  // The record describes these files only: a packing read back does not carry it.
  EXPECT_FALSE(read_packing((dir / "p.csv").string()).meta.contains("files"));

  // Another packing's CSV beside this JSON (what a crash between two renames would leave): refused.
  write_packing((dir / "other").string(), "p", awkward_packing(31));
  fs::copy_file(dir / "other" / "p.csv", dir / "p.csv", fs::copy_options::overwrite_existing);
  try {
    read_packing((dir / "p.csv").string());
    FAIL() << "a CSV that does not match its JSON's record was read";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("does not match the record"), std::string::npos) << e.what();
  }
  // Rewriting only the JSON keeps the record of the files on disk, whatever the new metadata says.
  write_packing(dir.string(), "q", awkward_packing(12));
  nlohmann::json stale = {{"files", {{"csv", {{"bytes", 1}, {"crc32", 2}}}}}, {"note", "rewritten"}};
  write_packing_meta(dir.string(), "q", stale);
  EXPECT_NO_THROW(read_packing((dir / "q.csv").string()));
  fs::remove_all(dir);
}

TEST(AtomicFile, DigestIsZlibsCrc32OfTheBytes) {
  const fs::path dir = fresh_dir("digest");
  fs::create_directories(dir);
  spit(dir / "t", "123456789");  // the CRC-32 check value of this string is 0xCBF43926
  const FileDigest d = digest_file(dir / "t");
  EXPECT_EQ(d.bytes, 9u);
  EXPECT_EQ(d.crc32, 0xCBF43926u);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace btr
