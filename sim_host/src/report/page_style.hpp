#pragma once
// The style of the report's HTML pages (the single-run report and the comparison): inline, so
// that a report folder opens anywhere without a server.

namespace harmoloc::sim_host {

inline constexpr const char* kPageCss = R"(
body { font-family: "DejaVu Sans", Helvetica, Arial, sans-serif; color: #222; margin: 2em auto;
       max-width: 940px; padding: 0 1em; line-height: 1.4; }
h1 { font-size: 1.7em; margin-bottom: 0.1em; }
h2 { font-size: 1.25em; margin-top: 1.8em; border-bottom: 1px solid #ddd; padding-bottom: 0.2em; }
p.subtitle { color: #555; margin-top: 0; font-size: 1.1em; }
table { border-collapse: collapse; margin: 0.6em 0; font-size: 0.95em; }
th, td { padding: 0.25em 0.8em; border-bottom: 1px solid #e4e4e4; text-align: right; }
th { background: #f4f4f4; }
td:first-child, th:first-child { text-align: left; }
td.over { color: #c62828; font-weight: bold; }
.files td { text-align: left; font-family: "DejaVu Sans Mono", monospace; font-size: 0.9em; }
figure { margin: 1.2em 0; }
figure img { max-width: 100%; border: 1px solid #e4e4e4; }
figcaption { color: #555; font-size: 0.9em; }
.note { color: #555; font-size: 0.9em; }
td.run { font-weight: bold; white-space: nowrap; }
.swatch { display: inline-block; width: 0.9em; height: 0.9em; margin-right: 0.4em;
          vertical-align: -0.1em; border-radius: 2px; }
.sections { display: flex; flex-wrap: wrap; gap: 0 2em; align-items: flex-start; }
)";

}  // namespace harmoloc::sim_host
