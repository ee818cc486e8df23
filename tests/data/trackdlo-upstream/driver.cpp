// A driver of our own for the upstream TrackDLO tracking step (RMDLO/trackdlo,
// MIT): reads one case from standard input, runs trackdlo::tracking_step once,
// prints the result. Built by make_goldens.py against the upstream sources in
// ../shared/upstream/trackdlo (never copied into this repository).
//
// Input (whitespace separated):
//   M N
//   visibility_threshold beta lambda alpha k_vis mu max_iter tol beta_pre_proc lambda_pre_proc lle_weight
//   sigma2
//   geodesic coordinates (M)
//   previous nodes (M rows of x y z)
//   points (N rows of x y z)
//   V visible node indices (V of them)
//   E extended visible node indices (E of them)
// Output: "sigma2 s", "guide G" + G rows, "priors P" + P rows "i x y z",
// "nodes M" + M rows.
#include <iomanip>
#include <iostream>
#include "trackdlo.h"

int main() {
    int m, n;
    std::cin >> m >> n;
    double vis, beta, lambda, alpha, k_vis, mu, tol, beta_pre, lambda_pre, lle;
    int max_iter;
    std::cin >> vis >> beta >> lambda >> alpha >> k_vis >> mu >> max_iter >> tol >> beta_pre >> lambda_pre >> lle;
    double sigma2;
    std::cin >> sigma2;
    std::vector<double> geo(m);
    for (auto &g : geo) std::cin >> g;
    MatrixXd y(m, 3), x(n, 3);
    for (int i = 0; i < m; i++) std::cin >> y(i, 0) >> y(i, 1) >> y(i, 2);
    for (int i = 0; i < n; i++) std::cin >> x(i, 0) >> x(i, 1) >> x(i, 2);
    int v, e;
    std::cin >> v;
    std::vector<int> visible(v);
    for (auto &k : visible) std::cin >> k;
    std::cin >> e;
    std::vector<int> extended(e);
    for (auto &k : extended) std::cin >> k;
    if (!std::cin) { std::cerr << "bad input\n"; return 2; }

    trackdlo t(m, vis, beta, lambda, alpha, k_vis, mu, max_iter, tol, beta_pre, lambda_pre, lle);
    t.initialize_geodesic_coord(geo);
    t.initialize_nodes(y);
    t.set_sigma2(sigma2);
    MatrixXd proj = MatrixXd::Zero(3, 4);
    t.tracking_step(x, visible, extended, proj, 480, 640);

    std::cout << std::setprecision(17);
    std::cout << "sigma2 " << t.get_sigma2() << "\n";
    MatrixXd g = t.get_guide_nodes();
    std::cout << "guide " << g.rows() << "\n";
    for (int i = 0; i < g.rows(); i++) std::cout << g(i, 0) << " " << g(i, 1) << " " << g(i, 2) << "\n";
    auto priors = t.get_correspondence_pairs();
    std::cout << "priors " << priors.size() << "\n";
    for (auto &p : priors) std::cout << p(0, 0) << " " << p(0, 1) << " " << p(0, 2) << " " << p(0, 3) << "\n";
    MatrixXd r = t.get_tracking_result();
    std::cout << "nodes " << r.rows() << "\n";
    for (int i = 0; i < r.rows(); i++) std::cout << r(i, 0) << " " << r(i, 1) << " " << r(i, 2) << "\n";
    return 0;
}
