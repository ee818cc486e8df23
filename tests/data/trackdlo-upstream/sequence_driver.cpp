// A driver of our own that runs upstream TrackDLO (RMDLO/trackdlo, MIT) over
// a whole sequence the way its ROS node (trackdlo_node.cpp) does each frame,
// without ROS or PCL: built by compare_sequences.py against the upstream
// sources in ../shared/upstream/trackdlo (never copied into this repository).
//
// Per frame, as the node's callback: BGR to HSV and one colour range
// (the node's single-colour mode; a hue range through 0 as two, as its
// multi-colour mode does for red), the occluder rectangles removed from the
// mask (the node's occlusion mask), every mask pixel deprojected with its
// depth (zero depth included, as the node does), a voxel grid of the node's
// leaf size (PCL's VoxelGrid: the centroid of each occupied voxel, voxels
// ordered by index), the node's visibility (nearest point within
// visibility_threshold, self-occlusion by edges drawn nearest first with
// cv::line of dlo_pixel_width, gaps up to d_vis filled), then
// trackdlo::tracking_step. The first frame only initialises, from the nodes
// given (the node takes them from initialize.py).
//
// Input (standard input, whitespace separated):
//   fx fy cx cy width height depth_scale
//   visibility_threshold beta lambda alpha k_vis mu max_iter tol beta_pre_proc lambda_pre_proc lle_weight
//   d_vis dlo_pixel_width leaf_size
//   h_lo s_lo v_lo h_hi s_hi v_hi
//   M, then M rows of x y z (the initial nodes)
//   F, then per frame: colour path, depth path, R, R rows of x y w h
// Output (standard output): the contract's result JSON.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "trackdlo.h"

using Eigen::MatrixXd;

// PCL's VoxelGrid on float points: the centroid of each occupied voxel,
// ordered by the voxel's index (x fastest).
static MatrixXd voxel_grid(const std::vector<Eigen::Vector3f> &pts, float leaf) {
    if (pts.empty()) return MatrixXd(0, 3);
    const float inv = 1.0f / leaf;
    Eigen::Vector3f lo = pts[0], hi = pts[0];
    for (const auto &p : pts) { lo = lo.cwiseMin(p); hi = hi.cwiseMax(p); }
    Eigen::Vector3i min_b, max_b;
    for (int k = 0; k < 3; k++) {
        min_b[k] = static_cast<int>(std::floor(lo[k] * inv));
        max_b[k] = static_cast<int>(std::floor(hi[k] * inv));
    }
    const long dx = max_b[0] - min_b[0] + 1, dy = max_b[1] - min_b[1] + 1;
    std::vector<std::pair<long, int>> idx;
    idx.reserve(pts.size());
    for (int n = 0; n < static_cast<int>(pts.size()); n++) {
        const auto &p = pts[n];
        long i = static_cast<long>(std::floor(p[0] * inv)) - min_b[0];
        long j = static_cast<long>(std::floor(p[1] * inv)) - min_b[1];
        long k = static_cast<long>(std::floor(p[2] * inv)) - min_b[2];
        idx.emplace_back(i + j * dx + k * dx * dy, n);
    }
    std::sort(idx.begin(), idx.end(), [](const auto &a, const auto &b) { return a.first < b.first; });
    std::vector<Eigen::Vector3d> out;
    for (size_t s = 0; s < idx.size();) {
        size_t e = s;
        Eigen::Vector4f c = Eigen::Vector4f::Zero();
        while (e < idx.size() && idx[e].first == idx[s].first) {
            c.head<3>() += pts[idx[e].second];
            c[3] += 1.0f;
            e++;
        }
        out.push_back((c.head<3>() / c[3]).cast<double>());
        s = e;
    }
    MatrixXd x(out.size(), 3);
    for (size_t n = 0; n < out.size(); n++) x.row(n) = out[n].transpose();
    return x;
}

int main() {
    double fx, fy, cx, cy, depth_scale;
    int width, height;
    std::cin >> fx >> fy >> cx >> cy >> width >> height >> depth_scale;
    double vis, beta, lambda, alpha, k_vis, mu, tol, beta_pre, lambda_pre, lle, d_vis, leaf;
    int max_iter, pixel_width;
    std::cin >> vis >> beta >> lambda >> alpha >> k_vis >> mu >> max_iter >> tol >> beta_pre >> lambda_pre >> lle;
    std::cin >> d_vis >> pixel_width >> leaf;
    int hsv[6];
    for (int &h : hsv) std::cin >> h;
    int m;
    std::cin >> m;
    MatrixXd init(m, 3);
    for (int i = 0; i < m; i++) std::cin >> init(i, 0) >> init(i, 1) >> init(i, 2);
    int frames;
    std::cin >> frames;
    if (!std::cin) { std::cerr << "bad input\n"; return 2; }

    MatrixXd proj = MatrixXd::Zero(3, 4);
    proj(0, 0) = fx; proj(0, 2) = cx; proj(1, 1) = fy; proj(1, 2) = cy; proj(2, 2) = 1.0;

    trackdlo tracker(m, vis, beta, lambda, alpha, k_vis, mu, max_iter, tol, beta_pre, lambda_pre, lle);
    std::vector<double> geo = {0.0};
    for (int i = 0; i < m - 1; i++) geo.push_back(geo.back() + (init.row(i + 1) - init.row(i)).norm());
    tracker.initialize_nodes(init);
    tracker.initialize_geodesic_coord(geo);
    MatrixXd Y = init;

    std::cout << std::setprecision(17) << "{\"algorithm\": \"trackdlo-upstream-cpp\", \"params\": {}, \"frames\": [\n";
    for (int f = 0; f < frames; f++) {
        std::string colour_path, depth_path;
        int rects;
        std::cin >> colour_path >> depth_path >> rects;
        std::vector<cv::Rect> occluders;
        for (int r = 0; r < rects; r++) {
            int x, y, w, h;
            std::cin >> x >> y >> w >> h;
            occluders.emplace_back(x, y, w, h);
        }
        if (!std::cin) { std::cerr << "bad input at frame " << f << "\n"; return 2; }
        std::vector<int> visible_nodes;
        double track_ms = 0.0;
        if (f > 0) {
            cv::Mat bgr = cv::imread(colour_path, cv::IMREAD_COLOR);
            cv::Mat depth = cv::imread(depth_path, cv::IMREAD_UNCHANGED);
            if (bgr.empty() || depth.empty() || depth.type() != CV_16UC1) {
                std::cerr << "frame " << f << ": cannot read " << colour_path << " / " << depth_path << "\n";
                return 2;
            }
            cv::Mat hsv_image, mask;
            cv::cvtColor(bgr, hsv_image, cv::COLOR_BGR2HSV);
            if (hsv[0] <= hsv[3]) {
                cv::inRange(hsv_image, cv::Scalar(hsv[0], hsv[1], hsv[2]), cv::Scalar(hsv[3], hsv[4], hsv[5]), mask);
            } else {
                // A hue range through 0 (red): two ranges OR'd, as the
                // node's multi-colour mode does for red.
                cv::Mat below;
                cv::inRange(hsv_image, cv::Scalar(hsv[0], hsv[1], hsv[2]), cv::Scalar(179, hsv[4], hsv[5]), mask);
                cv::inRange(hsv_image, cv::Scalar(0, hsv[1], hsv[2]), cv::Scalar(hsv[3], hsv[4], hsv[5]), below);
                cv::bitwise_or(mask, below, mask);
            }
            for (const auto &r : occluders) {
                cv::Rect clipped = r & cv::Rect(0, 0, mask.cols, mask.rows);
                if (clipped.area() > 0) mask(clipped).setTo(0);
            }
            std::vector<Eigen::Vector3f> pts;
            for (int i = 0; i < mask.rows; i++) {
                for (int j = 0; j < mask.cols; j++) {
                    if (mask.at<uchar>(i, j) == 0) continue;
                    double z = depth.at<uint16_t>(i, j) * depth_scale;
                    pts.emplace_back(static_cast<float>((j - cx) * z / fx), static_cast<float>((i - cy) * z / fy), static_cast<float>(z));
                }
            }
            MatrixXd X = voxel_grid(pts, static_cast<float>(leaf));

            // Visibility, as the node computes it.
            std::vector<double> nearest(m, 100000.0);
            for (int i = 0; i < m; i++)
                for (int n = 0; n < X.rows(); n++) nearest[i] = std::min(nearest[i], (Y.row(i) - X.row(n)).norm());
            std::vector<double> edge_dist;
            std::vector<int> order;
            for (int i = 0; i < m - 1; i++) {
                edge_dist.push_back(((Y.row(i) + Y.row(i + 1)) / 2).norm());
                order.push_back(i);
            }
            std::sort(order.begin(), order.end(), [&](int a, int b) { return edge_dist[a] < edge_dist[b]; });
            cv::Mat edges = cv::Mat::zeros(mask.rows, mask.cols, CV_8U);
            MatrixXd yh(m, 4);
            yh << Y, MatrixXd::Ones(m, 1);
            MatrixXd uv = (proj * yh.transpose()).transpose();
            auto seen = [&](int k) { return std::find(visible_nodes.begin(), visible_nodes.end(), k) != visible_nodes.end(); };
            for (int e : order) {
                int c1 = static_cast<int>(uv(e, 0) / uv(e, 2)), r1 = static_cast<int>(uv(e, 1) / uv(e, 2));
                int c2 = static_cast<int>(uv(e + 1, 0) / uv(e + 1, 2)), r2 = static_cast<int>(uv(e + 1, 1) / uv(e + 1, 2));
                // The node reads these pixels unchecked; a node outside the
                // image is taken as not drawn over here.
                auto free_at = [&](int r, int c) { return r < 0 || c < 0 || r >= edges.rows || c >= edges.cols || edges.at<uchar>(r, c) == 0; };
                if (free_at(r1, c1) && nearest[e] <= vis && !seen(e)) visible_nodes.push_back(e);
                if (free_at(r2, c2) && nearest[e + 1] <= vis && !seen(e + 1)) visible_nodes.push_back(e + 1);
                cv::line(edges, cv::Point(c1, r1), cv::Point(c2, r2), cv::Scalar(255, 255, 255), pixel_width);
            }
            std::sort(visible_nodes.begin(), visible_nodes.end());
            if (const char *dbg = std::getenv("TRACKDLO_DEBUG_FRAME"); dbg && std::atoi(dbg) == f) {
                std::cerr << "frame " << f << ": " << pts.size() << " mask points, " << X.rows() << " voxels; nearest mm:";
                for (int i = 0; i < m; i++) std::cerr << " " << i << ":" << nearest[i] * 1000.0;
                std::cerr << "\n";
            }
            if (visible_nodes.empty()) {
                // The node indexes visible_nodes[size - 1] here and crashes.
                std::cerr << "frame " << f << ": no visible node (upstream's node would crash)\n";
                return 3;
            }
            std::vector<int> extended;
            for (size_t i = 0; i + 1 < visible_nodes.size(); i++) {
                extended.push_back(visible_nodes[i]);
                if (std::fabs(geo[visible_nodes[i + 1]] - geo[visible_nodes[i]]) <= d_vis)
                    for (int j = 1; j < visible_nodes[i + 1] - visible_nodes[i]; j++) extended.push_back(visible_nodes[i] + j);
            }
            extended.push_back(visible_nodes.back());

            auto t0 = std::chrono::steady_clock::now();
            tracker.tracking_step(X, visible_nodes, extended, proj, mask.rows, mask.cols);
            track_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
            Y = tracker.get_tracking_result();
        }
        std::cout << (f ? ",\n" : "") << "{\"frame\": " << f << ", \"nodes\": [";
        for (int i = 0; i < m; i++) std::cout << (i ? ", " : "") << "[" << Y(i, 0) << ", " << Y(i, 1) << ", " << Y(i, 2) << "]";
        std::cout << "], \"visible\": [";
        for (int i = 0; i < m; i++) {
            bool v = f == 0 || std::find(visible_nodes.begin(), visible_nodes.end(), i) != visible_nodes.end();
            std::cout << (i ? ", " : "") << (v ? "true" : "false");
        }
        std::cout << "], \"track_ms\": " << track_ms << ", \"total_ms\": " << track_ms << "}";
    }
    std::cout << "\n]}\n";
    return 0;
}
