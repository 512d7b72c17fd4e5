// The live web view served at GET / by the metrics HTTP server: one self-contained HTML
// page (inline CSS, JavaScript and SVG; nothing fetched from elsewhere, so it works behind
// a firewall) that polls GET /sessions (sessions_json.h) every 0.5 s, lists the sessions
// and draws each one's sensors and estimated track in two panels, x-y (top view) and x-z
// (side view), with axes in metres. It links /metrics and /sessions.
//
// The page builds its DOM with createElement/textContent only: session labels come from
// clients and are never parsed as HTML.
#pragma once

#include <string_view>

namespace localizer::server {

// The page (UTF-8 HTML), a constant; serve as "text/html; charset=utf-8".
std::string_view LivePageHtml();

}  // namespace localizer::server
