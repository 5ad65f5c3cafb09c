from magdesign.cli import main

raise SystemExit(main())
