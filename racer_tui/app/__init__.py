"""The Textual app: `application` (the app, its sections and keys), `screens/` (one per
section and dialog), `widgets/`, the command palette, and the care a long-running app
needs on a live night (one key at a time, crash reports, memory kept flat).

Imports textual; the command line (`racer_tui.cli`) never imports it, except its entry
point, which opens the app when no command is given."""
