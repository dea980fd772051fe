#pragma once

#include <vtkCallbackCommand.h>
#include <vtkCommand.h>
#include <vtkObject.h>
#include <vtkSmartPointer.h>

#include <string>

namespace caps {

/// Collects VTK error events of one object (reader/writer) so they become a
/// SceneError instead of text on the console. While observed, VTK does not
/// print the error itself.
class VtkErrorCatcher
{
public:
  explicit VtkErrorCatcher(vtkObject* object) : object_(object)
  {
    callback_ = vtkSmartPointer<vtkCallbackCommand>::New();
    callback_->SetClientData(this);
    callback_->SetCallback([](vtkObject*, unsigned long, void* self, void* text) {
      auto* me = static_cast<VtkErrorCatcher*>(self);
      if (me->message_.empty() && text)
        me->message_ = clean(static_cast<const char*>(text));
      me->failed_ = true;
    });
    errorTag_ = object_->AddObserver(vtkCommand::ErrorEvent, callback_);
    warningTag_ = object_->AddObserver(vtkCommand::WarningEvent, vtkSmartPointer<vtkCallbackCommand>::New());
  }
  ~VtkErrorCatcher()
  {
    object_->RemoveObserver(errorTag_);
    object_->RemoveObserver(warningTag_);
  }
  VtkErrorCatcher(const VtkErrorCatcher&) = delete;
  VtkErrorCatcher& operator=(const VtkErrorCatcher&) = delete;

  bool failed() const { return failed_; }
  const std::string& message() const { return message_; }

private:
  // VTK's text starts with "ERROR: In <source file>, line N" and the object's
  // class and address; keep only the sentence meant for a person.
  static std::string clean(std::string text)
  {
    if (text.rfind("ERROR: In ", 0) == 0 && text.find('\n') != std::string::npos)
      text = text.substr(text.find('\n') + 1);
    if (const auto p = text.find("): "); p != std::string::npos && p < 80)
      text = text.substr(p + 3);
    while (!text.empty() && (text.back() == '\n' || text.back() == ' '))
      text.pop_back();
    return text;
  }

  vtkObject* object_;
  vtkSmartPointer<vtkCallbackCommand> callback_;
  unsigned long errorTag_ = 0, warningTag_ = 0;
  bool failed_ = false;
  std::string message_;
};

} // namespace caps
