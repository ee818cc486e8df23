//! The shared stages of one frame, the same for every tracking algorithm:
//! [`camera`] and [`frame`] (intrinsics, deprojection, the input images),
//! [`segmentation`] (HSV thresholds after the occlusion rectangles),
//! [`point_cloud`] (masked pixels with depth, voxel grid, pushed to the
//! rope's axis), [`initialisation`] (the ordered centre line and `M`
//! nodes when there is no state), and [`evidence`] (what the images say
//! about a point: hidden by something, or in free space), and
//! [`ego_motion`] (the camera's own motion, from the background) with
//! [`glance`] (whether it moved at all, cheaply), and
//! [`sharing`] (with several ropes, which rope each pixel belongs to), and
//! [`table`] (the plane the rope lies on).

pub mod camera;
pub mod ego_motion;
pub mod evidence;
pub mod frame;
pub mod glance;
pub mod initialisation;
pub mod point_cloud;
pub mod segmentation;
pub mod sharing;
pub mod table;
