"""heelstrike."""
