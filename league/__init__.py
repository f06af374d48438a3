"""League data: the SQLite store, rankings, nights and seasons, sync stores."""
