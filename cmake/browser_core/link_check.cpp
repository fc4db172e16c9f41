// browser_core_check's entry point (CMakeLists.txt, PMSTREAM_BROWSER_CORE): the check is that the browser's
// client core compiles with this directory's headers and links on its own; nothing runs.
int main() { return 0; }
