#include "cad/step_export.h"

#include <unistd.h>

#include <BRepTools.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_PrinterOStream.hxx>
#include <STEPCAFControl_Controller.hxx>
#include <STEPCAFControl_Writer.hxx>
#include <STEPControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp_Explorer.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <atomic>
#include <mutex>
#include <system_error>

#include "cad/brep_builder.h"
#include "io/errors.h"
#include "io/file_util.h"

namespace csgvox {
namespace {

namespace fs = std::filesystem;

// OpenCASCADE's reader and writer print statistics on stdout: silence them,
// and set the writer's format once. Not thread-safe in OpenCASCADE itself,
// so every use of the translators holds this lock.
std::mutex& translatorMutex() {
  static std::mutex m;
  return m;
}

void setUpTranslators() {
  static const bool done = [] {
    Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_PrinterOStream));
    STEPCAFControl_Controller::Init();  // declares the parameters set below
    return true;
  }();
  (void)done;
  Interface_Static::SetCVal("write.step.schema", "AP214IS");
  Interface_Static::SetCVal("write.step.unit", "MM");
  Interface_Static::SetIVal("write.stepcaf.subshapes.name", 1);
}

TCollection_ExtendedString extended(const std::string& s) {
  return TCollection_ExtendedString(s.c_str(), true);  // UTF-8
}

fs::path temporarySibling(const fs::path& path) {
  static std::atomic<unsigned> counter{0};
  return path.parent_path() / ("." + path.filename().string() + ".tmp-" +
                               std::to_string(::getpid()) + "-" + std::to_string(counter++));
}

}  // namespace

bool stepExportAvailable() { return true; }

BrepSummary writeStep(const fs::path& path, const CsgTree& tree, const StepOptions& options) {
  const cad::BrepResult brep = cad::buildBrep(tree, options);
  BrepSummary summary = cad::summarize(brep.shape);
  BRepTools::Clean(brep.shape);  // the face-naming triangulation is not part of the file

  std::lock_guard lock(translatorMutex());
  setUpTranslators();
  Handle(TDocStd_Document) doc;
  XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", doc);
  const Handle(XCAFDoc_ShapeTool) shapes = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
  const TDF_Label label = shapes->AddShape(brep.shape, false);
  TDataStd_Name::Set(label, extended(options.productName));
  for (const auto& [face, name] : brep.faceNames) {
    const TDF_Label sub = shapes->AddSubShape(label, face);
    if (sub.IsNull()) continue;
    TDataStd_Name::Set(sub, extended(name));
    ++summary.namedFaces;
  }

  const fs::path tmp = temporarySibling(path);
  try {
    STEPCAFControl_Writer writer;
    writer.SetNameMode(true);
    const bool transferred =
        writer.Transfer(doc, STEPControl_AsIs, nullptr, cad::cancelIndicator(options.control)->Start());
    if (options.control.cancelled()) throw CancelledError("the STEP export was cancelled");
    if (!transferred) {
      throw CadError(path.string() + ": OpenCASCADE cannot translate the solid to STEP");
    }
    if (writer.Write(tmp.c_str()) != IFSelect_RetDone) {
      throw IoError(path.string() + ": cannot be written");
    }
  } catch (const Standard_Failure& e) {
    std::error_code ec;
    fs::remove(tmp, ec);
    if (options.control.cancelled()) throw CancelledError("the STEP export was cancelled");
    throw CadError(path.string() + ": OpenCASCADE cannot write STEP: " + e.GetMessageString());
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
  XCAFApp_Application::GetApplication()->Close(doc);
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw IoError(path.string() + ": cannot be written (" + ec.message() + ")");
  }
  return summary;
}

BrepSummary readStepSummary(const fs::path& path) {
  requireReadableFile(path);
  std::lock_guard lock(translatorMutex());
  setUpTranslators();
  try {
    STEPControl_Reader reader;
    if (reader.ReadFile(path.c_str()) != IFSelect_RetDone) {
      throw ParseError(path.string() + ": not a readable STEP file");
    }
    reader.TransferRoots();
    const TopoDS_Shape shape = reader.OneShape();
    if (shape.IsNull()) throw ParseError(path.string() + ": holds no shape");
    return cad::summarize(shape);
  } catch (const Standard_Failure& e) {
    throw ParseError(path.string() + ": " + e.GetMessageString());
  }
}

}  // namespace csgvox
