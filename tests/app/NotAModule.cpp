// A shared library that is not a CAPS module (no entry points).
extern "C" int some_other_library_function()
{
  return 42;
}
