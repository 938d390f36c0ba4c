"""Material tables and small data shipped with translucency (installed as translucency.data)."""
