"""The command line: argument parsing and headless output, one module per command group
(`*_commands`), dispatched by `main`, the `racer-tui` entry point. Never imports textual;
`main` alone opens the app (`racer_tui.app`) when no command is given or a command asks
for it (`AppLaunch`)."""
