// The browser's client core includes no Boost (CMakeLists.txt, pms_browser_core): every Boost library,
// Asio and Beast among them, includes this header first.
#error "the browser's client core includes no Boost (docs/architecture.md, \"Layers\"): asio and Beast stay in the native transports"
