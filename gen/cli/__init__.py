"""The ``npstereo`` command line: :func:`.main.main` dispatches to one module per command
(``cmd_<name>``); :mod:`.arguments` holds the options and checks the commands share."""
