"""bench/decimation.py's measures of a proxy, on proxies whose answers are known."""

from translucency.geometry.synthetic import icosphere


def test_a_mesh_is_its_own_perfect_proxy_and_a_turned_triangle_is_counted():
    from decimation import proxy_quality

    points, triangles = icosphere(3, radius=10.0)
    same = proxy_quality(points, triangles, points, triangles)
    assert same["distance_max_mm"] < 1e-12 and same["open_edges"] == same["non_manifold_edges"] == 0
    assert same["triangles_against_the_mesh"] == 0 and same["edges"] == 3 * len(triangles) // 2
    assert 40.0 < same["smallest_angle_p1_deg"] < 60.0  # an icosphere's triangles are nearly equilateral
    turned = triangles.copy()
    turned[0] = turned[0, ::-1]
    assert proxy_quality(points, triangles, points, turned)["triangles_against_the_mesh"] == 1
    opened = proxy_quality(points, triangles, points, triangles[1:])
    assert opened["open_edges"] == 3 and opened["distance_max_mm"] < 1e-12  # its corners are on other triangles


def test_the_table_gives_the_distances_in_mean_edges_and_the_time_ratio():
    from decimation import markdown

    def way(seconds):
        return {
            "seconds": seconds, "peak_rss_tree_mb": 1024.0, "mean_edge_mm": 0.5, "distance_mean_mm": 0.05,
            "distance_p99_mm": 0.1, "distance_max_mm": 0.25, "open_edges": 0, "non_manifold_edges": 1,
            "triangles_against_the_mesh": 2, "smallest_angle_p1_deg": 4.5, "proxy_vertices": 10,
        }  # fmt: skip

    row = {"label": "x", "triangles": 90, "part_count": 4, "whole": way(2.0), "in parts": way(1.5)}
    table = markdown([row])
    assert "| x | 90 | in parts | 4 | 1.5 | 1.00 | 0.100 / 0.200 / 0.500 | 0 / 1 | 2 | 4.50 | 10 |" in table
    assert "x 0.75" in table
