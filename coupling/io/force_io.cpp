#include "coupling/io/force_io.h"

#include "coupling/io/atomic_file.h"


#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkTypeInt64Array.h>
#include <vtkXMLPolyDataWriter.h>

namespace btr {

namespace fs = std::filesystem;

namespace {

std::string csv_text(const ForceNetwork& net) {
  std::string out = "i,j,fx,fy,fz\n";
  out.reserve(out.size() + net.contacts.size() * 72);
  char row[160];
  for (const ContactForce& c : net.contacts) {
    std::snprintf(row, sizeof row, "%lld,%lld,%.17g,%.17g,%.17g\n", static_cast<long long>(c.i),
                  static_cast<long long>(c.j), c.f.x(), c.f.y(), c.f.z());
    out += row;
  }
  return out;
}

void write_vtp(const std::string& path, const Grains& grains, const ForceNetwork& net) {
  const vtkIdType n = static_cast<vtkIdType>(net.contacts.size());
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(2 * n);
  vtkNew<vtkCellArray> lines;
  vtkNew<vtkDoubleArray> force;
  force->SetName("force");
  force->SetNumberOfValues(n);
  vtkNew<vtkTypeInt64Array> ia, ja;
  ia->SetName("i");
  ja->SetName("j");
  ia->SetNumberOfValues(n);
  ja->SetNumberOfValues(n);
  for (vtkIdType k = 0; k < n; ++k) {
    const ContactForce& c = net.contacts[static_cast<std::size_t>(k)];
    const Grain& g = grains[static_cast<std::size_t>(c.i - 1)];
    Vec3 other;
    if (c.j > 0) {
      other = grains[static_cast<std::size_t>(c.j - 1)].x + c.shift;
    } else {
      // the contact point on the floor or wall: one radius from the centre against the normal
      const double f = c.f.norm();
      const Vec3 n_in = f > 0.0 ? Vec3(c.f / f) : Vec3(0.0, 0.0, c.j == 0 ? 1.0 : 0.0);
      other = g.x - g.r * n_in;
    }
    points->SetPoint(2 * k, g.x.x(), g.x.y(), g.x.z());
    points->SetPoint(2 * k + 1, other.x(), other.y(), other.z());
    const vtkIdType ids[2] = {2 * k, 2 * k + 1};
    lines->InsertNextCell(2, ids);
    force->SetValue(k, c.f.norm());
    ia->SetValue(k, c.i);
    ja->SetValue(k, c.j);
  }
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(points);
  poly->SetLines(lines);
  poly->GetCellData()->AddArray(force);
  poly->GetCellData()->AddArray(ia);
  poly->GetCellData()->AddArray(ja);
  poly->GetCellData()->SetActiveScalars("force");
  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->SetFileName(path.c_str());
  writer->SetInputData(poly);
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  writer->SetCompressorTypeToLZ4();
  writer->SetHeaderTypeToUInt64();
  if (writer->Write() != 1 || writer->GetErrorCode() != 0)
    throw std::runtime_error(path + ": VTK could not write it");
}

}  // namespace

void write_forces(const std::string& dir, const std::string& name, const Grains& grains, const ForceNetwork& net) {
  for (const ContactForce& c : net.contacts)
    if (c.i < 1 || c.i > static_cast<std::int64_t>(grains.size()) || c.j > static_cast<std::int64_t>(grains.size()))
      throw std::runtime_error("force network does not match the packing: contact " + std::to_string(c.i) + "-" +
                               std::to_string(c.j) + " with " + std::to_string(grains.size()) + " grains");
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir + ": cannot create the output folder: " + ec.message());
  const fs::path csv = fs::path(dir) / (name + ".forces.csv");
  const fs::path vtp = fs::path(dir) / (name + ".forces.vtp");
  TempFile csv_file(csv), vtp_file(vtp);
  write_vtp(vtp_file.temp().string(), grains, net);
  {
    std::FILE* f = std::fopen(csv_file.temp().c_str(), "wb");
    if (!f) throw std::runtime_error(csv.string() + ": cannot create " + csv_file.temp().string());
    const std::string text = csv_text(net);
    const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
    if (std::fclose(f) != 0 || !ok) throw std::runtime_error(csv.string() + ": write error");
  }
  csv_file.commit();
  vtp_file.commit();
}

}  // namespace btr
