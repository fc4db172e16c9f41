// The browser's client core has no asio (CMakeLists.txt, pms_browser_core): its transports are JavaScript's.
#error "the browser's client core includes no Boost.Asio (docs/architecture.md, \"Layers\"): asio stays in the native transports"
