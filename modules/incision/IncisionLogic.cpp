#include "modules/incision/IncisionLogic.h"

#include <stdexcept>

namespace caps {

const incision::ProcedureLibrary& IncisionLogic::procedures()
{
  if (!library_)
    library_ = incision::ProcedureLibrary::load(incision::defaultProceduresFolder());
  return *library_;
}

const incision::ProcedureLibrary& IncisionLogic::reloadProcedures(const std::filesystem::path& folder)
{
  library_ = incision::ProcedureLibrary::load(folder);
  return *library_;
}

incision::IncisionPlan IncisionLogic::placeProcedure(const std::string& id, const seg::RangeMap& skin,
                                                     const incision::SkinPoint& at,
                                                     const std::map<std::string, double>& values)
{
  const incision::ProcedureTemplate* procedure = procedures().find(id);
  if (!procedure)
  {
    std::string known;
    for (const auto& p : procedures().procedures())
      known += (known.empty() ? "" : ", ") + p.id();
    throw std::invalid_argument("no procedure '" + id + "'; the procedures are: " + known);
  }
  return procedure->place(skin, at, values);
}

} // namespace caps
