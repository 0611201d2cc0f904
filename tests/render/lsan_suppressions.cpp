// LeakSanitizer suppressions for the render tests (read by LSan at exit in
// BLVD_SANITIZE builds; an unused function otherwise).
//
// OSMesa 22.3 keeps the framebuffer made by OSMesaMakeCurrent (~280 bytes per
// context) after OSMesaDestroyContext, even when unbound first. It is Mesa's,
// bounded per context, and not reachable from blvd.
extern "C" const char* __lsan_default_suppressions();
extern "C" const char* __lsan_default_suppressions() { return "leak:libOSMesa.so\n"; }
