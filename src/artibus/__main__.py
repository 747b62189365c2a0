from artibus.cli import main

raise SystemExit(main())
